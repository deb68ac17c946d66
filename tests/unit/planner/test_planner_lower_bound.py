"""The lower bound: path length over the speed limit plus the turns the path forces over the turn limit."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from services.planner.lower_bound import lower_bound, turns_rad
from services.planner.shortest_path import solid_grid
from shared.geometry import Pose2D
from shared.world import load_world, parse_world

REPO_ROOT = Path(__file__).resolve().parents[3]


def test_turns_count_start_corners_and_goal_heading() -> None:
    square_corner = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    assert turns_rad(square_corner, 0.0, math.pi / 2) == pytest.approx(math.pi / 2)
    assert turns_rad(square_corner, math.pi, math.pi / 2) == pytest.approx(3 * math.pi / 2)
    assert turns_rad(np.array([[0.0, 0.0], [0.0, 0.0]]), 0.0, 1.0) == pytest.approx(1.0)


def test_glass_counts_as_solid_for_the_bound() -> None:
    world = load_world(REPO_ROOT / "deploy/worlds/glass_room.yaml")
    start, goal = Pose2D(-1.0, 4.2, -math.pi / 2), Pose2D(-1.0, 1.5, -math.pi / 2)
    bound = lower_bound(solid_grid(world), start, goal, 0.5, 1.5)
    straight = start.distance_to(goal)
    assert bound["path_length_m"] > straight + 1.0  # around the glass, not through it
    assert bound["lower_bound_s"] >= bound["path_length_m"] / 0.5


def _room_with_dock(x: float, y: float, yaw: float):  # type: ignore[no-untyped-def]

    return parse_world(
        {
            "name": "room",
            "bounds": [0.0, 0.0, 16.0, 12.0],
            "walls": [],
            "glass": [],
            "boxes": [],
            "docks": [{"id": "home", "pose": [x, y, yaw], "type": "charger"}],
            "robot": {"start": [1.0, 1.0, 0.0]},
        }
    )


@pytest.mark.parametrize("case", range(12))
def test_the_bound_exists_for_docks_at_any_angle(case: int) -> None:
    """A dock at any yaw (0.35 rad failed once: its rasterised cells reached the docking pose's cell)."""
    rng = np.random.default_rng(case)
    yaw = 0.35 if case == 0 else float(rng.uniform(-math.pi, math.pi))
    dock = Pose2D(float(rng.uniform(4.0, 12.0)), float(rng.uniform(3.0, 9.0)), yaw)
    world = _room_with_dock(dock.x, dock.y, dock.yaw)
    start = Pose2D(1.0, 1.0, float(rng.uniform(-math.pi, math.pi)))
    bound = lower_bound(solid_grid(world), start, world.docks[0].pose2d, 0.5, 1.5)
    straight = start.distance_to(dock)
    assert math.isfinite(bound["lower_bound_s"]) and bound["lower_bound_s"] > 0
    # No path is shorter than the straight line; in an empty room the shortest goes round the dock at most.
    assert straight - 1e-3 <= bound["path_length_m"] <= straight + 1.5  # (rounded to 0.1 mm)
    assert bound["lower_bound_s"] >= bound["path_length_m"] / 0.5 - 1e-3
