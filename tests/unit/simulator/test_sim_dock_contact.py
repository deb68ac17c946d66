"""Charging contacts: mated only when aligned and close; docking touches versus crashes into the dock."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from services.simulator.physics import Robot, SimParams
from shared.geometry import Pose2D
from shared.models.dock_contact import DockContactParams, dock_contact
from shared.models.footprint import polygon_distance
from shared.world import World, load_world

# dock_world: dock pose at the origin facing +x, its body from x=0.2 to x=0.4, y in [-0.2, 0.2].


def test_polygon_distance() -> None:
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert polygon_distance(square, square + [1.5, 0.0]) == pytest.approx(0.5)
    assert polygon_distance(square, square + [1.5, 1.5]) == pytest.approx(math.sqrt(0.5))
    assert polygon_distance(square, square + [0.5, 0.5]) == 0.0


@pytest.mark.parametrize(
    ("robot", "mated", "touching"),
    [
        pytest.param(Pose2D(0.0, 0.0, 0.0), True, True, id="docked"),
        pytest.param(Pose2D(-0.03, 0.0, 0.0), True, False, id="springs-reach"),
        pytest.param(Pose2D(-0.08, 0.0, 0.0), False, False, id="short"),
        pytest.param(Pose2D(-0.01, 0.06, 0.0), False, False, id="off-centre"),
        pytest.param(Pose2D(-0.028, 0.0, 0.2), False, True, id="skewed-corner-touching"),
        pytest.param(Pose2D(-0.02, 0.03, 0.08), True, False, id="within-tolerance"),
    ],
)
def test_mated_only_when_aligned_and_close(
    robot: Pose2D, mated: bool, touching: bool, dock_world: Callable[..., World]
) -> None:
    world = dock_world()
    contact = dock_contact(robot, world.docks, DockContactParams())
    assert contact.dock_id == "home"
    assert contact.mated is mated
    assert contact.touching is touching
    assert contact.along_error_m == pytest.approx(robot.x)
    assert contact.lateral_error_m == pytest.approx(robot.y)
    assert contact.yaw_error_rad == pytest.approx(robot.yaw)


def test_no_dock_nearby(dock_world: Callable[..., World]) -> None:
    dock_id, mated, touching, lateral, _, _ = dock_contact(
        Pose2D(-3.0, 0.0, 0.0), dock_world().docks, DockContactParams()
    )
    assert dock_id is None and not mated and not touching and math.isnan(lateral)


def drive(sim: Robot, v: float, w: float, seconds: float) -> None:
    for _ in range(round(seconds / sim.params.dt_s)):
        sim.step(v, w)


def test_driving_in_square_docks_without_a_collision(
    quiet: SimParams, dock_world: Callable[..., World]
) -> None:
    sim = Robot(dock_world(), params=quiet)
    drive(sim, 0.15, 0.0, 8.0)
    contact = sim.dock_contact()
    assert contact.mated and contact.touching
    assert contact.along_error_m == pytest.approx(0.0, abs=0.002)
    assert sim.drain_collisions() == []
    assert sum(sim.collision_counts.values()) == 0


def test_docking_in_the_seed_room(worlds_dir: Path) -> None:
    sim = Robot(load_world(worlds_dir / "seed_room.yaml"))
    sim.teleport(Pose2D(-1.0, 1.4, -math.pi / 2))
    assert not sim.dock_contact().mated
    drive(sim, 0.1, 0.0, 8.0)
    assert sim.dock_contact().mated and sim.drain_collisions() == []


def test_hitting_the_plate_skewed_at_speed_is_a_collision(
    quiet: SimParams, dock_world: Callable[..., World]
) -> None:
    sim = Robot(dock_world(), params=quiet)
    sim.teleport(Pose2D(-0.6, -0.35, 0.6))
    drive(sim, 0.4, 0.0, 3.0)
    events = sim.drain_collisions()
    assert [(e.kind, e.dock_id) for e in events] == [("dock", "home")]
    assert events[0].x_m == pytest.approx(0.2, abs=0.01)  # on the plate's face
    assert not sim.dock_contact().mated


def test_touching_the_plate_skewed_but_gently_is_not(
    quiet: SimParams, dock_world: Callable[..., World]
) -> None:
    sim = Robot(dock_world(), params=quiet)
    sim.teleport(Pose2D(-0.6, -0.35, 0.6))
    drive(sim, 0.08, 0.0, 12.0)
    assert sim.dock_contact().touching
    assert sim.drain_collisions() == []


def test_hitting_the_dock_body_side_is_a_collision(
    quiet: SimParams, dock_world: Callable[..., World]
) -> None:
    sim = Robot(dock_world(), params=quiet)
    sim.teleport(Pose2D(0.3, -1.0, math.pi / 2))
    drive(sim, 0.1, 0.0, 10.0)
    events = sim.drain_collisions()
    assert [e.kind for e in events] == ["dock"]
    assert events[0].y_m == pytest.approx(-0.2, abs=0.01)
    assert sim.pose.y == pytest.approx(-0.2 - 0.2, abs=0.005)


def test_teleport_onto_the_dock_pose_is_allowed(quiet: SimParams, dock_world: Callable[..., World]) -> None:
    sim = Robot(dock_world(), params=quiet)
    sim.teleport(Pose2D(0.0, 0.0, 0.0))
    drive(sim, 0.0, 0.0, 0.5)
    assert sim.dock_contact().mated
    assert sim.drain_collisions() == []
