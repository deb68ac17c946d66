"""Following a path given from outside (Nav2's ``follow_path``): the navigation's controller on a fixed
path, with no replanning and no recovery.

The controller, its speed limits near suspected glass, its collision check and the stopped-goal check
are those of a navigation goal. Where a navigation goal would replan or recover, this one ends and says
why, as Nav2's controller_server does: a collision ahead for ``blocked_timeout_s`` (NO_VALID_CONTROL),
no progress for ``progress_timeout_s`` (FAILED_TO_MAKE_PROGRESS), no robot pose (TF_ERROR).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from services.planner.behaviors import Outcome, Step
from services.planner.plan_monitor import ProgressChecker
from services.planner.pure_pursuit import FollowStatus, PurePursuitParams, RegulatedPurePursuit

if TYPE_CHECKING:  # the run's module reads the planner's parameters, which name FollowLimits
    from services.planner.navigation_run import NavSnapshot


@dataclass(frozen=True)
class FollowLimits:
    """When a followed path counts as done, stuck or blocked (the navigation's own parameters)."""

    controller_period_s: float
    required_movement_m: float
    required_rotation_rad: float
    progress_timeout_s: float
    blocked_timeout_s: float
    trans_stopped_mps: float
    rot_stopped_radps: float
    open_loop_acceleration: bool


class FollowPath:
    """Drive along ``poses`` (``(N, 3)`` in the map frame) to its last pose."""

    def __init__(self, poses: np.ndarray, follower: PurePursuitParams, limits: FollowLimits) -> None:
        if len(poses) < 1:
            raise ValueError("an empty path")
        self.follower = RegulatedPurePursuit(follower)
        self.follower.set_path(np.asarray(poses, dtype=float))
        self.limits = limits
        self._progress = ProgressChecker(
            limits.required_movement_m, limits.required_rotation_rad, limits.progress_timeout_s
        )
        self._last_s: float | None = None
        self._blocked_since_s: float | None = None

    def step(self, snap: NavSnapshot) -> Step:
        pose, grid = snap.pose, snap.grid
        if pose is None:
            return Step((0.0, 0.0), Outcome.NO_POSE, 0.0, "no robot pose")
        lim = self.limits
        period = lim.controller_period_s
        dt = period if self._last_s is None else min(max(snap.now_s - self._last_s, period), 4.0 * period)
        self._last_s = snap.now_s
        velocity = snap.velocity or snap.last_cmd
        reference = snap.last_cmd if lim.open_loop_acceleration else velocity
        command = self.follower.compute_velocity_command(pose, reference, dt, grid, snap.speed_limit_mps)
        last = self.follower.path[-1]
        to_goal = math.hypot(last[0] - pose.x, last[1] - pose.y)
        if command.status is FollowStatus.GOAL_REACHED:
            if abs(velocity[0]) > lim.trans_stopped_mps or abs(velocity[1]) > lim.rot_stopped_radps:
                return Step((0.0, 0.0), Outcome.RUNNING, to_goal)  # arrived once stopped there
            if not self.follower.confirm_goal(pose):
                return Step((0.0, 0.0), Outcome.RUNNING, to_goal)  # braked past it: the next step turns back
            return Step((0.0, 0.0), Outcome.SUCCEEDED, to_goal)
        if command.status is FollowStatus.COLLISION_AHEAD:
            if self._blocked_since_s is None:
                self._blocked_since_s = snap.now_s
            if snap.now_s - self._blocked_since_s > lim.blocked_timeout_s:
                return Step(
                    (0.0, 0.0),
                    Outcome.COLLISION_AHEAD,
                    to_goal,
                    f"an obstacle on the path ahead of ({pose.x:.2f}, {pose.y:.2f}) "
                    f"for {lim.blocked_timeout_s:g} s",
                )
            return Step((0.0, 0.0), Outcome.RUNNING, to_goal)
        self._blocked_since_s = None
        if not self._progress.check(pose, snap.now_s):
            return Step(
                (0.0, 0.0), Outcome.NO_PROGRESS, to_goal, f"no progress for {lim.progress_timeout_s:g} s"
            )
        return Step((command.linear_mps, command.angular_radps), Outcome.RUNNING, to_goal)
