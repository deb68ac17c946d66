"""The lower bound: path length over the speed limit plus the turns the path forces over the turn limit."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from services.planner.lower_bound import lower_bound, turns_rad
from services.planner.shortest_path import solid_grid
from shared.geometry import Pose2D
from shared.world import load_world

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
