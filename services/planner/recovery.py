"""The back-up recovery: reverse a short, straight distance, only over cells the costmap shows free.

After nav2_behaviors ``BackUp``: drive backwards at ``speed_mps`` until ``distance_m`` is covered, the
time allowance runs out, or the footprint would touch a lethal cell within the rest of the distance
(checked every step against the current costmap, so a reversing robot never backs into what it can
see). The node follows it with a costmap clear and a replan.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from services.planner.costmap import LETHAL_OBSTACLE, NO_INFORMATION, CostGrid
from services.planner.pure_pursuit import project_arc
from shared.geometry import Pose2D


class GlassClearing(enum.Enum):
    """How much of the glass memory a recovery forgets."""

    KEEP = "keep"
    AROUND_ROBOT = "around_robot"
    ALL = "all"


def glass_clearing(recovery: int, planning_failed: bool) -> GlassClearing:
    """What recovery number ``recovery`` (1, 2, ...) forgets of the glass memory.

    Glass is known only from the forward-looking sonar and cannot be seen again from beside it, so odd
    recoveries keep it; even ones forget it round the robot, in case a spurious echo is what blocks the way
    (glass farther off stays: forgetting a pane's end the sonar saw once, a robot replanned past it and
    drove into it). When the planner still finds no path after that, from the fourth recovery on, the
    glass that blocks it may lie anywhere: all of it is forgotten, as Nav2 clears its whole global
    costmap when computing a path fails.
    """
    if recovery % 2 == 1:
        return GlassClearing.KEEP
    if planning_failed and recovery >= 4:
        return GlassClearing.ALL
    return GlassClearing.AROUND_ROBOT


class BackUpStatus(enum.Enum):
    RUNNING = "running"
    DONE = "done"
    BLOCKED = "blocked"
    TIMED_OUT = "timed_out"


@dataclass(frozen=True)
class BackUpParams:
    distance_m: float = 0.15
    speed_mps: float = 0.1
    time_allowance_s: float = 4.0
    robot_length_m: float = 0.40
    robot_width_m: float = 0.30

    def __post_init__(self) -> None:
        for name in ("distance_m", "speed_mps", "time_allowance_s", "robot_length_m", "robot_width_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value}")


class BackUp:
    """One back-up manoeuvre at a time: :meth:`start`, then :meth:`step` every control cycle."""

    def __init__(self, params: BackUpParams | None = None) -> None:
        self.params = params or BackUpParams()
        self._start: Pose2D | None = None
        self._start_s = 0.0

    def start(self, pose: Pose2D, now_s: float) -> None:
        self._start = pose
        self._start_s = now_s

    def travelled_m(self, pose: Pose2D) -> float:
        if self._start is None:
            return 0.0
        return math.hypot(pose.x - self._start.x, pose.y - self._start.y)

    def step(self, pose: Pose2D, now_s: float, grid: CostGrid) -> tuple[float, BackUpStatus]:
        """``(linear velocity to command, status)``; the velocity is negative while running, else 0."""
        p = self.params
        if self._start is None:
            return 0.0, BackUpStatus.DONE
        remaining = p.distance_m - self.travelled_m(pose)
        if remaining <= 0.0:
            return 0.0, BackUpStatus.DONE
        if now_s - self._start_s > p.time_allowance_s:
            return 0.0, BackUpStatus.TIMED_OUT
        if self.blocked_behind(pose, remaining, grid):
            return 0.0, BackUpStatus.BLOCKED
        return -p.speed_mps, BackUpStatus.RUNNING

    def blocked_behind(self, pose: Pose2D, distance_m: float, grid: CostGrid) -> bool:
        """Would reversing ``distance_m`` straight back put the footprint on a lethal cell?"""
        p = self.params
        step_m = grid.frame.resolution_m
        count = max(1, math.ceil(distance_m / step_m))
        times = np.arange(1, count + 1) * (distance_m / count) / p.speed_mps
        poses = project_arc(pose, -p.speed_mps, 0.0, times)
        costs = grid.footprint_costs(poses, p.robot_length_m, p.robot_width_m)
        return bool(np.any((costs >= LETHAL_OBSTACLE) & (costs != NO_INFORMATION)))
