"""Watching a plan while it is followed: distance left, whether new obstacles block it, whether the
robot is making progress.

- :class:`ActivePlan` keeps the path with its arc lengths and the costs it was planned through, so a
  later costmap can tell "newly blocked" (an obstacle appeared on it) from "was already costly" (a start
  inside inflation), and the node replans only for the former.
- :class:`ProgressChecker` is nav2's ``SimpleProgressChecker``: the robot must move
  ``required_movement_m`` (or turn ``required_rotation_rad``) within ``time_allowance_s``, else it is stuck.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from services.planner.costmap import INSCRIBED_INFLATED_OBSTACLE, NO_INFORMATION, CostGrid
from shared.geometry import Pose2D, wrap_angle


@dataclass(frozen=True, eq=False)
class ActivePlan:
    """A path being followed: ``(N, 3)`` poses, cumulative arc length, and the costs when planned."""

    poses: np.ndarray
    arc_length_m: np.ndarray
    planned_costs: np.ndarray
    planned_at_s: float

    @classmethod
    def from_poses(cls, poses: np.ndarray, planned_on: CostGrid, planned_at_s: float) -> ActivePlan:
        poses = np.asarray(poses, dtype=float).reshape(-1, 3)
        steps = np.hypot(*np.diff(poses[:, :2], axis=0).T) if len(poses) > 1 else np.zeros(0)
        arc = np.concatenate([[0.0], np.cumsum(steps)])
        return cls(poses, arc, planned_on.costs_at(poses[:, :2]), planned_at_s)

    @property
    def length_m(self) -> float:
        return float(self.arc_length_m[-1])

    def remaining_m(self, closest_index: int, pose: Pose2D) -> float:
        """Distance to the goal along the path from the robot's closest pose, plus the gap to it."""
        i = min(max(closest_index, 0), len(self.poses) - 1)
        gap = math.hypot(self.poses[i, 0] - pose.x, self.poses[i, 1] - pose.y)
        return gap + float(self.arc_length_m[-1] - self.arc_length_m[i])

    def newly_blocked(self, grid: CostGrid, closest_index: int, skip_m: float) -> bool:
        """Whether a cell ahead (beyond ``skip_m`` from the closest pose) is now inscribed or lethal
        though it was not when planned. Unknown cells do not count (the planner never entered them)."""
        i = min(max(closest_index, 0), len(self.poses) - 1)
        start = int(np.searchsorted(self.arc_length_m, self.arc_length_m[i] + skip_m, side="left"))
        if start >= len(self.poses):
            return False
        now = grid.costs_at(self.poses[start:, :2])
        before = self.planned_costs[start:]
        blocked = (now >= INSCRIBED_INFLATED_OBSTACLE) & (now != NO_INFORMATION)
        was_blocked = (before >= INSCRIBED_INFLATED_OBSTACLE) & (before != NO_INFORMATION)
        return bool(np.any(blocked & ~was_blocked))


class ProgressChecker:
    """nav2 ``SimpleProgressChecker`` with rotation counted as progress (turning in place is work)."""

    def __init__(
        self, required_movement_m: float, required_rotation_rad: float, time_allowance_s: float
    ) -> None:
        self.required_movement_m = required_movement_m
        self.required_rotation_rad = required_rotation_rad
        self.time_allowance_s = time_allowance_s
        self._baseline: Pose2D | None = None
        self._baseline_s = 0.0

    def reset(self, pose: Pose2D | None = None, now_s: float = 0.0) -> None:
        self._baseline = pose
        self._baseline_s = now_s

    def check(self, pose: Pose2D, now_s: float) -> bool:
        """True while the robot is making progress; False once it has been stuck too long."""
        base = self._baseline
        if base is None or now_s < self._baseline_s:
            self.reset(pose, now_s)
            return True
        moved = math.hypot(pose.x - base.x, pose.y - base.y) >= self.required_movement_m
        turned = abs(wrap_angle(pose.yaw - base.yaw)) >= self.required_rotation_rad
        if moved or turned:
            self.reset(pose, now_s)
            return True
        return now_s - self._baseline_s <= self.time_allowance_s
