import math
from pathlib import Path

import pytest

from services.docking.approach import (
    GRACEFUL_STAGING_OFFSET_M,
    LineApproachOffsets,
    dock_frame_error,
    docking_target,
    graceful_staging_pose,
    line_approach,
    within_contact_reach,
)
from shared.geometry import Pose2D
from shared.world import load_world

SEED_ROOM_WORLD = Path(__file__).resolve().parents[3] / "deploy" / "worlds" / "seed_room.yaml"
SEED_DOCK = Pose2D(-1.0, 0.83, -math.pi / 2)


def assert_pose(actual: Pose2D, x: float, y: float, yaw: float, tol: float = 1e-4) -> None:
    assert actual.x == pytest.approx(x, abs=tol)
    assert actual.y == pytest.approx(y, abs=tol)
    assert math.remainder(actual.yaw - yaw, 2 * math.pi) == pytest.approx(0.0, abs=tol)


def test_seed_room_dock_reproduces_the_original_waypoints() -> None:
    approach = line_approach(SEED_DOCK)
    assert_pose(approach.staging_goal, 0.0, 2.0, 0.0)
    assert_pose(approach.line_waypoint, -1.0, 2.0, -1.5708)
    assert_pose(approach.front_waypoint, -1.0, 1.4, -1.5708)
    assert_pose(approach.dock, -1.0, 0.83, -1.5708)
    assert approach.goals == (approach.line_waypoint, approach.front_waypoint, approach.dock)


def test_seed_room_world_file_dock_gives_the_same_waypoints() -> None:
    world = load_world(SEED_ROOM_WORLD)
    approach = line_approach(world.dock("home").pose2d)
    assert_pose(approach.staging_goal, 0.0, 2.0, 0.0)
    assert_pose(approach.front_waypoint, -1.0, 1.4, -1.5708)


@pytest.mark.parametrize("yaw", [0.0, 0.7, math.pi / 2, -2.5, math.pi - 1e-3])
def test_waypoints_move_rigidly_with_the_dock(yaw: float) -> None:
    dock = Pose2D(2.0, -1.0, yaw)
    approach = line_approach(dock)
    for pose, (along, lateral, yaw_offset) in [
        (approach.line_waypoint, (-1.17, 0.0, 0.0)),
        (approach.front_waypoint, (-0.57, 0.0, 0.0)),
        (approach.staging_goal, (-1.17, 1.0, math.pi / 2)),
    ]:
        error = dock_frame_error(pose, dock)
        assert error.along_m == pytest.approx(along)
        assert error.lateral_m == pytest.approx(lateral)
        assert error.yaw_rad == pytest.approx(math.remainder(yaw_offset, 2 * math.pi))


def test_offsets_are_parameters() -> None:
    offsets = LineApproachOffsets(line_waypoint_back_m=2.0, front_waypoint_back_m=1.0, staging_left_m=-0.5)
    approach = line_approach(Pose2D(0.0, 0.0, 0.0), offsets)
    assert_pose(approach.line_waypoint, -2.0, 0.0, 0.0)
    assert_pose(approach.front_waypoint, -1.0, 0.0, 0.0)
    assert_pose(approach.staging_goal, -2.0, -0.5, math.pi / 2)


def test_graceful_staging_is_behind_the_dock_facing_it() -> None:
    staging = graceful_staging_pose(SEED_DOCK)
    assert_pose(staging, -1.0, 0.83 + GRACEFUL_STAGING_OFFSET_M, -math.pi / 2)
    assert_pose(graceful_staging_pose(SEED_DOCK, 0.5), -1.0, 1.33, -math.pi / 2)


def test_docking_target_is_past_the_dock_pose() -> None:
    assert_pose(docking_target(SEED_DOCK, 0.2), -1.0, 0.63, -math.pi / 2)


def test_dock_frame_error_signs() -> None:
    # Behind the dock (north of it, since it faces south), shifted to the dock's left (east), turned left.
    robot = Pose2D(-0.9, 1.23, -math.pi / 2 + 0.1)
    error = dock_frame_error(robot, SEED_DOCK)
    assert error.along_m == pytest.approx(-0.4)
    assert error.lateral_m == pytest.approx(0.1)
    assert error.yaw_rad == pytest.approx(0.1)
    assert not within_contact_reach(robot, SEED_DOCK, 0.05)
    assert within_contact_reach(Pose2D(-1.0, 0.87, -math.pi / 2), SEED_DOCK, 0.05)
