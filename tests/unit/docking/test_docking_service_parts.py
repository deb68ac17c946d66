"""The approach controllers' adapters, the service's parameters and the ``zendock dock`` helpers."""

from __future__ import annotations

import pytest

from deploy.commands.dock import ERROR_NAMES, STATE_NAMES, describe_dock_feedback
from services.docking.approach import dock_frame_error, graceful_staging_pose, line_approach, offset_along
from services.docking.approach_control import (
    ARRIVED,
    MISALIGNED,
    GracefulApproach,
    SeedApproach,
    back_off_command,
    back_off_gains,
    graceful_params_with_speed,
)
from services.docking.errors import DockingErrorCode, DockingState
from services.docking.kinematics import DiffDriveModel
from services.docking.params import Params
from services.docking.task_io import Velocity
from shared import structs
from shared.config_errors import ConfigError
from shared.interfaces.docking import DockRobotFeedback
from shared.messages import Duration
from tests.support.processes import REPO_ROOT
from tests.unit.docking.harness import SEED_DOCK

SEED_ROOM = str(REPO_ROOT / "deploy/worlds/seed_room.yaml")


def test_graceful_approach_arrives_when_it_pushes_without_moving() -> None:
    approach = GracefulApproach()
    approach.begin(SEED_DOCK)
    pose = offset_along(SEED_DOCK, -0.03)
    t = 0.0
    first = approach.command(t, pose, 0.0, (0.0, 0.0))
    assert first is not ARRIVED and first.linear_x_mps > 0.03
    while t < 0.6:
        t += 0.05
        assert approach.command(t, pose, 0.0, (0.0, 0.0)) is not ARRIVED
    t += 0.05
    assert approach.command(t, pose, 0.0, (0.0, 0.0)) is ARRIVED


def test_held_commands_do_not_count_as_a_stall() -> None:
    approach = GracefulApproach()
    approach.begin(SEED_DOCK)
    pose = graceful_staging_pose(SEED_DOCK)
    for i in range(40):  # two seconds held by an obstacle: the robot stands still, nothing was sent
        assert approach.command(0.05 * i, pose, 0.0, (0.0, 0.0)) is not ARRIVED
        approach.hold()


def test_graceful_approach_arrives_when_it_believes_it_is_past_the_dock() -> None:
    approach = GracefulApproach()
    approach.begin(SEED_DOCK)
    assert approach.command(0.0, offset_along(SEED_DOCK, 0.03), 0.0, None) is ARRIVED


def test_graceful_speed_limit() -> None:
    params = graceful_params_with_speed(0.15)
    assert params.gains.v_linear_max_mps == 0.15 and params.gains.v_linear_min_mps <= 0.15
    approach = GracefulApproach(params)
    approach.begin(SEED_DOCK)
    command = approach.command(0.0, graceful_staging_pose(SEED_DOCK), 0.0, None)
    assert command is not ARRIVED and 0.0 < command.linear_x_mps <= 0.15


def test_seed_approach_follows_its_waypoints_and_moves_them_with_the_dock() -> None:
    approach = SeedApproach()
    assert approach.staging_pose(SEED_DOCK) == line_approach(SEED_DOCK).staging_goal
    approach.begin(SEED_DOCK)
    line_waypoint, front_waypoint, dock = line_approach(SEED_DOCK).goals
    assert approach.command(0.0, line_waypoint, 0.0, None) == Velocity(0.0, 0.0)
    assert approach.goal_index == 1  # standing on the first waypoint: on to the front waypoint
    moved = offset_along(SEED_DOCK, 0.0, 0.1)  # the dock is 10 cm further to its left (+x here)
    approach.update_dock(moved)
    # On the old front waypoint, the new one is 10 cm to the robot's left: turn towards it.
    assert approach.command(0.1, front_waypoint, 0.0, None) == Velocity(0.0, 0.1)
    assert approach.goal_index == 1
    assert approach.command(0.2, line_approach(moved).front_waypoint, 0.0, None) == Velocity(0.0, 0.0)
    assert approach.goal_index == 2
    assert approach.command(0.3, moved, 0.0, None) is ARRIVED


def test_backing_off_reverses_to_staging() -> None:
    robot = DiffDriveModel(SEED_DOCK.compose(type(SEED_DOCK)(0.0, 0.01, 0.03)))
    target = graceful_staging_pose(SEED_DOCK)
    gains = back_off_gains(0.2)
    for _ in range(200):
        command = back_off_command(target, robot.pose, gains)
        assert command.linear_x_mps <= 0.0 and abs(command.linear_x_mps) <= 0.2 + 1e-9
        for _ in range(10):
            robot.step(command.linear_x_mps, command.angular_z_radps, 0.005)
        if robot.pose.distance_to(target) < 0.05:
            break
    error = dock_frame_error(robot.pose, SEED_DOCK)
    assert robot.pose.distance_to(target) < 0.05 and abs(error.yaw_rad) < 0.05


# --- parameters --------------------------------------------------------------------------------------


def test_params_take_a_world_file_as_the_dock_database() -> None:
    params = structs.validate(Params, {"dock_database": SEED_ROOM}, "params")
    assert (params.controller, params.low_battery_threshold, params.max_retries) == ("graceful", 0.25, 3)
    patrol = structs.validate(
        Params, {"dock_database": SEED_ROOM, "patrol": [[1, 2, 0.5]], "controller": "seed"}, "params"
    )
    assert patrol.patrol == [(1.0, 2.0, 0.5)]


@pytest.mark.parametrize(
    "bad, field",
    [
        ({"controller": "pid"}, "controller"),
        ({"resume_at": 0.2}, "resume_at"),
        ({"dock_database": "/nonexistent/docks.yaml"}, "dock_database"),
        ({"max_approach_speed_mps": 0.8}, "max_approach_speed_mps"),
        ({"unknown": 1}, "unknown"),
        ({"world": SEED_ROOM}, "world"),
    ],
)
def test_params_refuse_bad_values(bad: dict, field: str) -> None:  # type: ignore[type-arg]
    with pytest.raises(ConfigError, match=rf"^params: {field}\b"):
        structs.validate(Params, {"dock_database": SEED_ROOM} | bad, "params")


# --- zendock dock -------------------------------------------------------------------------------------


def test_cli_names_match_the_service_codes() -> None:
    assert {v: STATE_NAMES[v] for v in STATE_NAMES} == {int(s): s.name for s in DockingState}
    for code in DockingErrorCode:
        if code >= 900:
            assert ERROR_NAMES[int(code)] == code.name


def test_feedback_lines_change_with_state_and_retries() -> None:
    feedback = DockRobotFeedback(
        state=DockRobotFeedback.CONTROLLING, docking_time=Duration.from_sec(12.34), num_retries=0
    )
    key, line = describe_dock_feedback(feedback)
    assert line == "   12.3 s  CONTROLLING" and key == (3, 0)
    feedback.num_retries = 2
    key2, line2 = describe_dock_feedback(feedback)
    assert key2 != key and line2.endswith("CONTROLLING  (retry 2)")


def test_a_late_tick_is_no_stall_and_a_stall_away_from_the_plate_takes_longer() -> None:
    approach = GracefulApproach()
    approach.begin(SEED_DOCK)
    pose = offset_along(SEED_DOCK, -0.03)
    t = 0.0
    approach.command(t, pose, 0.0, (0.0, 0.0))
    for gap in (0.3, 0.3, 0.3, 0.3):  # pushing, not moving, but every tick late: the base braked by itself
        t += gap
        assert approach.command(t, pose, 0.0, (0.0, 0.0)) is not ARRIVED
    away = GracefulApproach()
    away.begin(SEED_DOCK)
    stuck = offset_along(SEED_DOCK, -0.3)  # a corner caught on something, 30 cm short of the dock pose
    t = 0.0
    while t < away.arrival.far_stall_time_s:
        assert away.command(t, stuck, 0.0, (0.0, 0.0)) is not ARRIVED, t
        t += 0.05
    assert away.command(t + 0.05, stuck, 0.0, (0.0, 0.0)) is ARRIVED


def test_coming_up_to_the_plate_off_its_axis_gives_up() -> None:
    approach = GracefulApproach()
    approach.begin(SEED_DOCK)
    assert approach.command(0.0, offset_along(SEED_DOCK, -0.08, 0.035), 0.0, None) is MISALIGNED
    assert approach.command(0.05, offset_along(SEED_DOCK, -0.08, 0.0, 0.25), 0.0, None) is MISALIGNED
    assert approach.command(0.1, offset_along(SEED_DOCK, -0.08, 0.01, 0.05), 0.0, None) not in (
        ARRIVED,
        MISALIGNED,
    )
    assert approach.command(0.15, offset_along(SEED_DOCK, -0.3, 0.06), 0.0, None) not in (ARRIVED, MISALIGNED)
