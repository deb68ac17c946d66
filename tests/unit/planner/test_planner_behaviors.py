"""The behaviours' motions: they reach their target, stop short of what the costmap shows, keep time."""

from __future__ import annotations

import math

import pytest

from services.planner.behaviors import BehaviorParams, DriveStraight, Outcome, Spin, Wait
from shared.geometry import Pose2D
from tests.unit.planner.rooms import room_grid

PARAMS = BehaviorParams(
    robot_length_m=0.4, robot_width_m=0.3, max_linear_vel_mps=0.5, max_angular_vel_radps=1.5
)


def _grid(walls: list | None = None):  # type: ignore[no-untyped-def]
    return room_grid(4.0, walls)


def test_back_up_reverses_its_distance_then_stops() -> None:
    grid = _grid()
    backup = DriveStraight(0.15, -0.1, 0.0, PARAMS)
    assert backup.step(Pose2D(2.0, 1.5, 0.0), 0.0, grid).cmd == (-0.1, 0.0)
    assert backup.step(Pose2D(1.86, 1.5, 0.0), 1.4, grid).outcome is Outcome.RUNNING
    done = backup.step(Pose2D(1.84, 1.5, 0.0), 1.6, grid)
    assert (done.cmd, done.outcome) == ((0.0, 0.0), Outcome.SUCCEEDED)
    assert done.progress == pytest.approx(0.16)


def test_drive_never_goes_into_what_the_costmap_shows() -> None:
    grid = _grid(walls=[[[1.6, 0.0], [1.6, 3.0]]])
    close_to_wall = Pose2D(1.85, 1.5, 0.0)  # rear edge 0.05 m in front of the wall
    backwards = DriveStraight(0.15, -0.1, 0.0, PARAMS).step(close_to_wall, 0.0, grid)
    assert backwards.outcome is Outcome.COLLISION_AHEAD and backwards.cmd == (0.0, 0.0)
    assert "backwards" in backwards.reason
    forwards = DriveStraight(0.15, 0.1, 0.0, PARAMS).step(close_to_wall, 0.0, grid)
    assert forwards.outcome is Outcome.RUNNING  # the way ahead is free
    facing_wall = Pose2D(1.95, 1.5, math.pi)
    assert (
        DriveStraight(0.5, 0.2, 0.0, PARAMS).step(facing_wall, 0.0, grid).outcome is Outcome.COLLISION_AHEAD
    )


def test_drive_keeps_its_time_allowance_and_speed_limit() -> None:
    grid = _grid()
    drive = DriveStraight(1.0, 2.0, 2.0, PARAMS)
    assert drive.step(Pose2D(1.0, 1.5, 0.0), 0.0, grid).cmd == (0.5, 0.0)  # capped at the top speed
    late = drive.step(Pose2D(1.3, 1.5, 0.0), 2.5, grid)
    assert late.outcome is Outcome.TIMED_OUT and "0.30 of 1.00 m" in late.reason


def test_drive_refuses_what_it_cannot_do() -> None:
    with pytest.raises(ValueError, match="speed"):
        DriveStraight(0.5, 0.0, 0.0, PARAMS)
    with pytest.raises(ValueError, match="distance"):
        DriveStraight(0.0, 0.1, 0.0, PARAMS)


def test_spin_turns_its_angle_both_ways_and_slows_at_the_end() -> None:
    grid = _grid()
    for target in (1.57, -1.57):
        spin = Spin(target, 10.0, PARAMS)
        yaw, now = 0.0, 0.0
        step = spin.step(Pose2D(2.0, 1.5, yaw), now, grid)
        speeds = []
        while step.outcome is Outcome.RUNNING:
            assert step.cmd is not None and step.cmd[0] == 0.0
            speeds.append(abs(step.cmd[1]))
            yaw += step.cmd[1] * 0.05
            now += 0.05
            step = spin.step(Pose2D(2.0, 1.5, math.remainder(yaw, math.tau)), now, grid)
        assert step.outcome is Outcome.SUCCEEDED
        assert step.progress == pytest.approx(1.57, abs=PARAMS.yaw_tolerance_rad + 0.08)
        assert math.copysign(1.0, yaw) == math.copysign(1.0, target)
        assert max(speeds) == pytest.approx(1.5) and speeds[-1] < 0.6


def test_spin_counts_whole_turns_across_the_wrap() -> None:
    spin = Spin(2 * math.tau, 0.0, PARAMS)
    yaw = 3.0
    for i in range(200):
        step = spin.step(Pose2D(2.0, 1.5, math.remainder(yaw, math.tau)), i * 0.05, None)
        if step.outcome is not Outcome.RUNNING:
            break
        yaw += step.cmd[1] * 0.05  # type: ignore[index]
    assert step.outcome is Outcome.SUCCEEDED and step.progress == pytest.approx(2 * math.tau, abs=0.1)


def test_spin_stops_where_its_corners_would_touch_a_wall() -> None:
    grid = _grid(walls=[[[2.2, 0.0], [2.2, 3.0]]])
    beside_wall = Pose2D(2.0, 1.5, math.pi / 2)  # its side 0.05 m from the wall: a corner sweeps into it
    step = Spin(1.57, 10.0, PARAMS).step(beside_wall, 0.0, grid)
    assert step.outcome is Outcome.COLLISION_AHEAD and "corners" in step.reason
    in_the_open = Pose2D(1.0, 1.5, math.pi / 2)
    assert Spin(1.57, 10.0, PARAMS).step(in_the_open, 0.0, grid).outcome is Outcome.RUNNING


def test_without_a_pose_a_motion_ends_at_once() -> None:
    assert Spin(1.0, 0.0, PARAMS).step(None, 0.0, None).outcome is Outcome.NO_POSE
    assert DriveStraight(1.0, 0.1, 0.0, PARAMS).step(None, 0.0, None).outcome is Outcome.NO_POSE


def test_wait_counts_down_and_commands_nothing() -> None:
    wait = Wait(2.0)
    first = wait.step(None, 10.0, None)
    assert (first.cmd, first.outcome, first.progress) == (None, Outcome.RUNNING, 2.0)
    assert wait.step(None, 11.5, None).progress == pytest.approx(0.5)
    assert wait.step(None, 12.0, None).outcome is Outcome.SUCCEEDED


def test_a_robot_touching_an_obstacle_may_still_back_away_from_it() -> None:
    grid = _grid(walls=[[[2.2, 0.0], [2.2, 3.0]]])
    touching = Pose2D(2.0, 1.5, 0.0)  # its front edge on the wall's cells
    assert DriveStraight(0.15, -0.1, 0.0, PARAMS).step(touching, 0.0, grid).outcome is Outcome.RUNNING
    assert DriveStraight(0.15, 0.1, 0.0, PARAMS).step(touching, 0.0, grid).outcome is Outcome.COLLISION_AHEAD
