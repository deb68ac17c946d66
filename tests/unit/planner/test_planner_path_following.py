"""follow_path: navigation's controller on a given path reaches its end, and ends with a reason when it
cannot (an obstacle on the path, no pose)."""

from __future__ import annotations

import math

import numpy as np

from services.planner.behaviors import Outcome
from services.planner.navigation_run import NavSnapshot
from services.planner.params import Params
from services.planner.path_following import FollowPath
from shared.geometry import Pose2D
from tests.unit.planner.rooms import room_grid

PARAMS = Params()


def _grid(walls: list | None = None):  # type: ignore[no-untyped-def]
    return room_grid(6.0, walls)


def _drive(follow: FollowPath, grid, pose: Pose2D, seconds: float):  # type: ignore[no-untyped-def]
    """Step the controller with a robot that does exactly what it is told; the last step and the pose."""
    dt, now, cmd = 0.05, 0.0, (0.0, 0.0)
    step = None
    while now < seconds:
        snap = NavSnapshot(now, now, pose, 0.0, True, cmd, grid, False, cmd)
        step = follow.step(snap)
        if step.outcome is not Outcome.RUNNING:
            return step, pose
        cmd = step.cmd or (0.0, 0.0)
        yaw = pose.yaw + cmd[1] * dt
        pose = Pose2D(pose.x + cmd[0] * dt * math.cos(yaw), pose.y + cmd[0] * dt * math.sin(yaw), yaw)
        now += dt
    return step, pose


def _line(x0: float, x1: float, y: float) -> np.ndarray:
    xs = np.arange(x0, x1 + 1e-9, 0.05)
    return np.column_stack([xs, np.full_like(xs, y), np.zeros_like(xs)])


def test_a_given_path_is_driven_to_its_end() -> None:
    follow = FollowPath(_line(1.0, 4.0, 1.5), PARAMS.follower_params(), PARAMS.follow_limits())
    step, pose = _drive(follow, _grid(), Pose2D(1.0, 1.5, 0.0), 30.0)
    assert step is not None and step.outcome is Outcome.SUCCEEDED, step
    assert math.hypot(pose.x - 4.0, pose.y - 1.5) < PARAMS.xy_goal_tolerance_m + 0.05


def test_an_obstacle_on_the_path_ends_it_with_a_reason_and_no_contact() -> None:
    grid = _grid(walls=[[[3.0, 0.0], [3.0, 3.0]]])  # across the path: no replanning round it
    follow = FollowPath(_line(1.0, 5.0, 1.5), PARAMS.follower_params(), PARAMS.follow_limits())
    step, pose = _drive(follow, grid, Pose2D(1.0, 1.5, 0.0), 60.0)
    assert step is not None and step.outcome is Outcome.COLLISION_AHEAD, step
    assert "obstacle on the path" in step.reason
    assert pose.x + PARAMS.robot_length_m / 2 < 3.0  # stopped short of the wall


def test_without_a_pose_it_ends_at_once() -> None:
    follow = FollowPath(_line(1.0, 2.0, 1.5), PARAMS.follower_params(), PARAMS.follow_limits())
    step = follow.step(NavSnapshot(0.0, 0.0, None, 0.0, False, None, _grid(), False))
    assert step.outcome is Outcome.NO_POSE
