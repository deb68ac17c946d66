"""Short motions on request, after Nav2's behavior_server: spin in place, drive straight (back up or on
heading), wait.

Each is stepped once a control cycle with the robot's pose and the current costmap, and answers with the
command to publish and whether it is done. Before every step the rest of the motion, up to
``simulate_ahead_s`` of it, is laid over the costmap with the robot's footprint, from the first step on
(not where the robot stands: a robot touching an obstacle, as one is when a recovery starts, may still back
away from it); a motion that would put
the footprint on a lethal cell stops there with COLLISION_AHEAD (a robot next to a wall or a pane the
sonar heard refuses at its first step). As in Nav2, a time allowance of 0 means no limit.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from services.planner.costmap import LETHAL_OBSTACLE, NO_INFORMATION, CostGrid
from services.planner.pure_pursuit import project_arc
from shared.geometry import Pose2D, wrap_angle


class Outcome(enum.Enum):
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    TIMED_OUT = "timed out"
    COLLISION_AHEAD = "collision ahead"
    NO_POSE = "no pose"
    NO_PROGRESS = "no progress"


@dataclass(frozen=True)
class BehaviorParams:
    robot_length_m: float
    robot_width_m: float
    max_linear_vel_mps: float
    max_angular_vel_radps: float
    min_angular_vel_radps: float = 0.4
    angular_accel_radps2: float = 3.0
    #: How much of the motion ahead is checked against the costmap (Nav2's simulate_ahead_time).
    simulate_ahead_s: float = 2.0
    #: A spin is done within this of its target.
    yaw_tolerance_rad: float = 0.02


@dataclass(frozen=True)
class Step:
    """One control cycle's answer: the command (None: send none), the outcome so far, the progress (rad
    turned, m travelled, s left) and, when it ended badly, why."""

    cmd: tuple[float, float] | None
    outcome: Outcome
    progress: float
    reason: str = ""


def _lethal(costs: np.ndarray) -> bool:
    return bool(np.any((costs >= LETHAL_OBSTACLE) & (costs != NO_INFORMATION)))


class _Timed:
    def __init__(self, time_allowance_s: float) -> None:
        self.time_allowance_s = time_allowance_s
        self.started_s: float | None = None

    def elapsed_s(self, now_s: float) -> float:
        return 0.0 if self.started_s is None else now_s - self.started_s

    def out_of_time(self, now_s: float) -> bool:
        return self.time_allowance_s > 0.0 and self.elapsed_s(now_s) > self.time_allowance_s


class Spin(_Timed):
    """Turn in place by ``target_yaw_rad`` (counter-clockwise positive), slowing towards the end."""

    def __init__(self, target_yaw_rad: float, time_allowance_s: float, params: BehaviorParams) -> None:
        super().__init__(time_allowance_s)
        self.target_rad = target_yaw_rad
        self.params = params
        self.turned_rad = 0.0
        self._last_yaw: float | None = None

    def step(self, pose: Pose2D | None, now_s: float, grid: CostGrid | None) -> Step:
        if pose is None:
            return Step((0.0, 0.0), Outcome.NO_POSE, abs(self.turned_rad), "no robot pose")
        if self.started_s is None:
            self.started_s = now_s
        if self._last_yaw is not None:
            self.turned_rad += wrap_angle(pose.yaw - self._last_yaw)
        self._last_yaw = pose.yaw
        p = self.params
        remaining = abs(self.target_rad) - abs(self.turned_rad)
        if remaining <= p.yaw_tolerance_rad:
            return Step((0.0, 0.0), Outcome.SUCCEEDED, abs(self.turned_rad))
        if self.out_of_time(now_s):
            return Step(
                (0.0, 0.0),
                Outcome.TIMED_OUT,
                abs(self.turned_rad),
                f"turned {abs(self.turned_rad):.2f} of {abs(self.target_rad):.2f} rad "
                f"in the time allowance of {self.time_allowance_s:g} s",
            )
        speed = min(p.max_angular_vel_radps, math.sqrt(2.0 * p.angular_accel_radps2 * remaining))
        speed = max(speed, min(p.min_angular_vel_radps, p.max_angular_vel_radps))
        w = math.copysign(speed, self.target_rad)
        if grid is not None:
            ahead_rad = min(remaining, speed * p.simulate_ahead_s)
            count = max(1, math.ceil(ahead_rad / 0.05))
            times = np.arange(1, count + 1) * (ahead_rad / count) / speed  # from the first step on
            poses = project_arc(pose, 0.0, w, times)
            if _lethal(grid.footprint_costs(poses, p.robot_length_m, p.robot_width_m)):
                return Step(
                    (0.0, 0.0),
                    Outcome.COLLISION_AHEAD,
                    abs(self.turned_rad),
                    f"turning further would put the robot's corners on an obstacle at ({pose.x:.2f}, {pose.y:.2f})",
                )
        return Step((0.0, w), Outcome.RUNNING, abs(self.turned_rad))


class DriveStraight(_Timed):
    """Drive ``distance_m`` straight at ``speed_mps`` (negative: backwards), checking the way ahead."""

    def __init__(
        self, distance_m: float, speed_mps: float, time_allowance_s: float, params: BehaviorParams
    ) -> None:
        super().__init__(time_allowance_s)
        if not (distance_m > 0.0 and math.isfinite(distance_m)):
            raise ValueError(f"the distance must be positive, got {distance_m}")
        if speed_mps == 0.0 or not math.isfinite(speed_mps):
            raise ValueError(f"the speed must not be zero, got {speed_mps}")
        self.distance_m = distance_m
        self.speed_mps = math.copysign(min(abs(speed_mps), params.max_linear_vel_mps), speed_mps)
        self.params = params
        self._start: Pose2D | None = None
        self.travelled_m = 0.0

    def step(self, pose: Pose2D | None, now_s: float, grid: CostGrid | None) -> Step:
        if pose is None:
            return Step((0.0, 0.0), Outcome.NO_POSE, self.travelled_m, "no robot pose")
        if self._start is None:
            self._start, self.started_s = pose, now_s
        self.travelled_m = math.hypot(pose.x - self._start.x, pose.y - self._start.y)
        p = self.params
        remaining = self.distance_m - self.travelled_m
        if remaining <= 0.0:
            return Step((0.0, 0.0), Outcome.SUCCEEDED, self.travelled_m)
        if self.out_of_time(now_s):
            return Step(
                (0.0, 0.0),
                Outcome.TIMED_OUT,
                self.travelled_m,
                f"drove {self.travelled_m:.2f} of {self.distance_m:.2f} m "
                f"in the time allowance of {self.time_allowance_s:g} s",
            )
        if grid is not None:
            ahead_m = min(remaining, abs(self.speed_mps) * p.simulate_ahead_s)
            count = max(1, math.ceil(ahead_m / (0.5 * grid.frame.resolution_m)))
            times = (
                np.arange(1, count + 1) * (ahead_m / count) / abs(self.speed_mps)
            )  # from the first step on
            poses = project_arc(pose, self.speed_mps, 0.0, times)
            if _lethal(grid.footprint_costs(poses, p.robot_length_m, p.robot_width_m)):
                way = "backwards" if self.speed_mps < 0 else "forwards"
                return Step(
                    (0.0, 0.0),
                    Outcome.COLLISION_AHEAD,
                    self.travelled_m,
                    f"an obstacle within {ahead_m:.2f} m {way} of ({pose.x:.2f}, {pose.y:.2f})",
                )
        return Step((self.speed_mps, 0.0), Outcome.RUNNING, self.travelled_m)


class Wait(_Timed):
    """Let ``duration_s`` pass: no command is sent, as Nav2's Wait sends none (a user's teleop goes on)."""

    def __init__(self, duration_s: float) -> None:
        super().__init__(0.0)
        self.duration_s = duration_s

    def step(self, pose: Pose2D | None, now_s: float, grid: CostGrid | None) -> Step:
        if self.started_s is None:
            self.started_s = now_s
        left = self.duration_s - self.elapsed_s(now_s)
        if left <= 0.0:
            return Step(None, Outcome.SUCCEEDED, 0.0)
        return Step(None, Outcome.RUNNING, left)
