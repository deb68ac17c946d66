"""The seed docking behaviour: a bang-bang line approach through waypoints, and the low-battery trigger.

This is zendock's baseline, kept deliberately simple so the graceful controller has something honest
to be measured against. Stepped at 10 Hz, for each goal in turn the robot

1. turns on the spot (``+-angular_speed``) while the bearing to the goal is off by more than
   ``heading_tolerance_rad``, otherwise drives straight at ``linear_speed``, until it is within
   ``distance_tolerance_m`` of the goal position;
2. then turns on the spot to the goal's yaw (within ``yaw_goal_tolerance_rad``); once it has started
   this, it never goes back to step 1 for the same goal;
3. then moves on to the next goal. After the last goal it commands zero velocity (idle) for ever.

The goal yaw error is ``goal_yaw - yaw`` *without* wrapping, as in the original behaviour: from a yaw
near +pi it turns the long way round to -pi/2. ``wrap_yaw_goal_error=True`` takes the short way.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass

from shared.geometry import Pose2D


@dataclass(frozen=True, slots=True)
class LineApproachParams:
    """Speeds and tolerances of the line approach; defaults are the seed behaviour's numbers."""

    linear_speed_mps: float = 0.08
    angular_speed_radps: float = 0.1
    distance_tolerance_m: float = 0.05
    heading_tolerance_rad: float = 0.05
    yaw_goal_tolerance_rad: float = 0.05
    #: The seed behaviour does not wrap the goal yaw error; set True to turn the short way.
    wrap_yaw_goal_error: bool = False
    #: The period the controller is meant to be stepped at.
    control_period_s: float = 0.1


class LinePhase(enum.Enum):
    """What the line controller does for its current goal."""

    SEEK_POSITION = "seek_position"  # turning towards, or driving to, the goal position
    ALIGN_YAW = "align_yaw"  # at the goal position, turning to the goal yaw
    IDLE = "idle"  # every goal reached: zero command


class LineApproachController:
    """Bang-bang waypoint follower; ``step`` takes the robot's map pose, returns ``(linear_x, angular_z)``."""

    def __init__(self, goals: Sequence[Pose2D], params: LineApproachParams | None = None) -> None:
        if not goals:
            raise ValueError("the line approach needs at least one goal")
        self.goals: tuple[Pose2D, ...] = tuple(goals)
        self.params = params or LineApproachParams()
        self.goal_idx = 0
        self.reached_distance_goal = False

    def reset(self) -> None:
        """Start again from the first goal."""
        self.goal_idx = 0
        self.reached_distance_goal = False

    @property
    def is_idle(self) -> bool:
        return self.goal_idx >= len(self.goals)

    @property
    def phase(self) -> LinePhase:
        if self.is_idle:
            return LinePhase.IDLE
        return LinePhase.ALIGN_YAW if self.reached_distance_goal else LinePhase.SEEK_POSITION

    @property
    def current_goal(self) -> Pose2D | None:
        return None if self.is_idle else self.goals[self.goal_idx]

    def distance_to_goal_m(self, pose_x: float, pose_y: float) -> float:
        goal = self.goals[self.goal_idx]
        return math.hypot(goal.x - pose_x, goal.y - pose_y)

    def heading_error_rad(self, pose_x: float, pose_y: float, pose_yaw: float) -> float:
        """Bearing to the goal position minus the robot's yaw, brought into [-pi, pi] by one 2*pi step."""
        goal = self.goals[self.goal_idx]
        error = math.atan2(goal.y - pose_y, goal.x - pose_x) - pose_yaw
        if error > math.pi:
            error -= 2.0 * math.pi
        if error < -math.pi:
            error += 2.0 * math.pi
        return error

    def yaw_goal_error_rad(self, pose_yaw: float) -> float:
        error = self.goals[self.goal_idx].yaw - pose_yaw
        if self.params.wrap_yaw_goal_error:
            error = (error + math.pi) % (2.0 * math.pi) - math.pi
        return error

    def step(self, pose_x: float, pose_y: float, pose_yaw: float) -> tuple[float, float]:
        """One control tick: the velocity command ``(linear_x m/s, angular_z rad/s)`` for this pose."""
        if self.is_idle:
            return (0.0, 0.0)
        p = self.params
        distance = self.distance_to_goal_m(pose_x, pose_y)
        heading_error = self.heading_error_rad(pose_x, pose_y, pose_yaw)
        yaw_goal_error = self.yaw_goal_error_rad(pose_yaw)
        linear_x = 0.0
        angular_z = 0.0
        if abs(distance) > p.distance_tolerance_m and not self.reached_distance_goal:
            if abs(heading_error) > p.heading_tolerance_rad:
                angular_z = p.angular_speed_radps if heading_error > 0 else -p.angular_speed_radps
            else:
                linear_x = p.linear_speed_mps
        elif abs(yaw_goal_error) > p.yaw_goal_tolerance_rad:
            angular_z = p.angular_speed_radps if yaw_goal_error > 0 else -p.angular_speed_radps
            self.reached_distance_goal = True
        else:
            last_goal = self.goal_idx == len(self.goals) - 1
            self.goal_idx += 1
            # Intermediate goals clear the flag for the next goal; the last one leaves it set.
            self.reached_distance_goal = last_goal
        return (linear_x, angular_z)


class LowBatteryTrigger:
    """Decides when a battery reading should start a docking run.

    Fires once when the charge fraction drops below ``threshold`` (previous reading at or above it, this
    one below), and also when the very first reading is already below it, so a robot that boots on a
    low battery still goes home. While charging it never fires. It re-arms when a reading is back at or
    above the threshold, or when charging is seen (so leaving the dock still low fires again).
    Readings that are not finite (``BatteryState.percentage`` is NaN when unknown) are ignored.
    """

    def __init__(self, threshold: float = 0.25) -> None:
        if not 0.0 < threshold <= 1.0:
            raise ValueError(f"threshold must be a charge fraction in (0, 1], got {threshold}")
        self.threshold = threshold
        self._armed = True
        self.last_percentage: float | None = None

    @property
    def armed(self) -> bool:
        return self._armed

    def reset(self) -> None:
        self._armed = True
        self.last_percentage = None

    def update(self, percentage: float, charging: bool = False) -> bool:
        """Feed one reading (fraction 0..1); True exactly when docking should start now."""
        if not math.isfinite(percentage):
            return False
        self.last_percentage = percentage
        if charging or percentage >= self.threshold:
            self._armed = True
            return False
        if self._armed:
            self._armed = False
            return True
        return False
