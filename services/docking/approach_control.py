"""The final approach's controllers behind one interface, and the backing-off law.

:class:`SeedApproach` runs the line approach (:mod:`services.docking.seed_controller`) through its
waypoints and reports arrival once its last goal is reached. :class:`GracefulApproach` runs the graceful
law (:mod:`services.docking.graceful`) on the latency-compensated pose; since it aims past the plate it
never "arrives" by itself: the approach ends with charging, or when the robot has pushed against
something without moving for ``stall_time_s`` (the plate, when charging does not come; longer away
from it), or when the robot believes it is already past the dock pose (it is mislocalised); it gives
up when the robot comes up to the plate too far off the dock's axis to mate. Both accept a newer dock pose
every tick. :func:`back_off_command` drives backwards along the dock's axis to a pose behind it.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, replace
from typing import Protocol

from services.docking.approach import (
    DEFAULT_LINE_OFFSETS,
    LineApproachOffsets,
    dock_frame_error,
    graceful_staging_pose,
    line_approach,
)
from services.docking.graceful import (
    ZENDOCK_PARAMS,
    ZENDOCK_TUNED,
    GracefulDockController,
    GracefulDockParams,
    GracefulGains,
    smooth_control_law,
)
from services.docking.seed_controller import LineApproachController, LineApproachParams
from services.docking.task_io import Velocity
from shared.geometry import Pose2D


class Arrival(enum.Enum):
    """The approach has ended without charging (yet): wait for the charger to report (ARRIVED), or the
    robot has come up to the plate too far off its axis to mate (MISALIGNED): back off and try again."""

    ARRIVED = "arrived"
    MISALIGNED = "misaligned"


ARRIVED = Arrival.ARRIVED
MISALIGNED = Arrival.MISALIGNED


class ApproachController(Protocol):
    """A final-approach controller: a map pose in, a command (or arrival) out."""

    period_s: float

    def staging_pose(self, dock_pose: Pose2D) -> Pose2D: ...

    def curves_in_from(self, pose: Pose2D, dock_pose: Pose2D) -> bool:
        """Whether, taking over at ``pose``, the approach would set off on a curve rather than stop to turn
        on the spot first."""

    def begin(self, dock_pose: Pose2D) -> None: ...

    def update_dock(self, dock_pose: Pose2D) -> None: ...

    def hold(self) -> None:
        """The last command was not sent: the robot was held still (an obstacle)."""

    def command(
        self, now_s: float, pose: Pose2D, pose_age_s: float, base_twist: tuple[float, float] | None
    ) -> Velocity | Arrival: ...


class SeedApproach:
    """The line approach at 10 Hz: goals derived from the dock pose, bang-bang commands."""

    def __init__(
        self, params: LineApproachParams | None = None, offsets: LineApproachOffsets = DEFAULT_LINE_OFFSETS
    ):
        self.params = params or LineApproachParams()
        self.offsets = offsets
        self.period_s = self.params.control_period_s
        self._controller: LineApproachController | None = None

    def staging_pose(self, dock_pose: Pose2D) -> Pose2D:
        return line_approach(dock_pose, self.offsets).staging_goal

    def curves_in_from(self, pose: Pose2D, dock_pose: Pose2D) -> bool:
        return False  # it turns on the spot to each of its goals

    def begin(self, dock_pose: Pose2D) -> None:
        self._controller = LineApproachController(line_approach(dock_pose, self.offsets).goals, self.params)

    def update_dock(self, dock_pose: Pose2D) -> None:
        """Move the goals with a refined dock pose; the goal being worked on stays the same."""
        if self._controller is not None:
            self._controller.goals = line_approach(dock_pose, self.offsets).goals

    def hold(self) -> None:
        pass

    @property
    def goal_index(self) -> int:
        return self._controller.goal_idx if self._controller is not None else 0

    def command(
        self, now_s: float, pose: Pose2D, pose_age_s: float, base_twist: tuple[float, float] | None
    ) -> Velocity | Arrival:
        if self._controller is None:
            raise RuntimeError("begin() first")
        if self._controller.is_idle:
            return ARRIVED
        linear, angular = self._controller.step(pose.x, pose.y, pose.yaw)
        if self._controller.is_idle:
            return ARRIVED
        return Velocity(linear, angular)


@dataclass(frozen=True, slots=True)
class ArrivalParams:
    """When the graceful approach stops by itself (besides charging)."""

    #: Commanding at least this forward speed...
    stall_command_mps: float = 0.03
    #: ...while odometry shows less than this...
    stall_speed_mps: float = 0.01
    #: ...for this long means the robot is pushing against something: the plate, when it is within
    #: ``plate_zone_m`` of the dock pose (along the axis), ...
    stall_time_s: float = 0.6
    plate_zone_m: float = 0.12
    #: ... something else (a corner on the dock's body) when it is further away.
    far_stall_time_s: float = 2.0
    #: A control tick this much later than the previous one restarts the stall clock: the base stops by
    #: itself when commands stop coming, which is no stall.
    max_tick_gap_s: float = 0.2
    #: Believing to be this far past the dock pose means the robot is on the plate (or mislocalised).
    overshoot_m: float = 0.02
    #: This close to the dock pose (along its axis) the robot must be within these of it, or it would
    #: meet the plate askew (a late control tick let it swing): MISALIGNED.
    misaligned_zone_m: float = 0.12
    misaligned_lateral_m: float = 0.03
    misaligned_yaw_rad: float = 0.2


class GracefulApproach:
    """The graceful law at 20 Hz on the estimated pose; arrival by stall or overshoot (see module doc)."""

    def __init__(
        self,
        params: GracefulDockParams = ZENDOCK_PARAMS,
        staging_offset_m: float = 0.7,
        arrival: ArrivalParams | None = None,
    ) -> None:
        self.params = params
        self.staging_offset_m = staging_offset_m
        self.arrival = arrival or ArrivalParams()
        self.period_s = params.control_period_s
        self._controller: GracefulDockController | None = None
        self._last_s: float | None = None
        self._stalled_since_s: float | None = None
        self._pushed = False

    def staging_pose(self, dock_pose: Pose2D) -> Pose2D:
        return graceful_staging_pose(dock_pose, self.staging_offset_m)

    def entry_curvature(self, pose: Pose2D, dock_pose: Pose2D) -> float:
        """The curvature (1/m) the law would first steer on from ``pose``."""
        law = GracefulDockController(dock_pose, replace(self.params, pose_estimator=None))
        return smooth_control_law(law.target_for(pose), pose, law.gains_at(pose)).curvature_per_m

    def curves_in_from(self, pose: Pose2D, dock_pose: Pose2D) -> bool:
        limit = self.params.pivot_curvature_per_m
        return limit is None or abs(self.entry_curvature(pose, dock_pose)) <= limit

    def begin(self, dock_pose: Pose2D) -> None:
        self._controller = GracefulDockController(dock_pose, self.params)
        self._controller.reset()
        self._last_s = None
        self._stalled_since_s = None
        self._pushed = False

    def update_dock(self, dock_pose: Pose2D) -> None:
        if self._controller is not None:
            self._controller.set_dock_pose(dock_pose)

    def hold(self) -> None:
        """The robot was held still instead: a stall is only counted while pushing commands go out, and
        the commands just computed are not on their way to the base."""
        self._pushed = False
        self._stalled_since_s = None
        if self._controller is not None:
            self._controller.forget_commands()

    def command(
        self, now_s: float, pose: Pose2D, pose_age_s: float, base_twist: tuple[float, float] | None
    ) -> Velocity | Arrival:
        controller = self._controller
        if controller is None:
            raise RuntimeError("begin() first")
        dt = self.period_s if self._last_s is None else max(0.0, now_s - self._last_s)
        self._last_s = now_s
        error = dock_frame_error(pose, controller.dock_pose)
        along_m = error.along_m
        if along_m >= self.arrival.overshoot_m:
            return ARRIVED
        a = self.arrival
        if along_m >= -a.misaligned_zone_m and (
            abs(error.lateral_m) > a.misaligned_lateral_m or abs(error.yaw_rad) > a.misaligned_yaw_rad
        ):
            return MISALIGNED
        command = controller.compute(pose, dt, pose_age_s, base_twist)
        pushing = command.linear_x_mps >= a.stall_command_mps
        stopped = base_twist is not None and abs(base_twist[0]) < a.stall_speed_mps
        if pushing and self._pushed and stopped and dt <= a.max_tick_gap_s:
            stall_time_s = a.stall_time_s if along_m >= -a.plate_zone_m else a.far_stall_time_s
            if self._stalled_since_s is None:
                self._stalled_since_s = now_s
            elif now_s - self._stalled_since_s >= stall_time_s:
                return ARRIVED
        else:
            self._stalled_since_s = None
        self._pushed = pushing
        return Velocity(command.linear_x_mps, command.angular_z_radps)


def graceful_params_with_speed(
    max_speed_mps: float, base: GracefulDockParams = ZENDOCK_PARAMS
) -> GracefulDockParams:
    """The tuned docking parameters with a different top speed (the minimum speed is kept below it)."""
    gains = replace(
        base.gains,
        v_linear_max_mps=max_speed_mps,
        v_linear_min_mps=min(base.gains.v_linear_min_mps, max_speed_mps),
    )
    return replace(base, gains=gains)


def back_off_gains(max_speed_mps: float = 0.2, base: GracefulGains = ZENDOCK_TUNED) -> GracefulGains:
    """Gentle gains for driving backwards off the dock (Nav2 undocks with the same law, reversed)."""
    return replace(base, v_linear_max_mps=max_speed_mps, v_linear_min_mps=min(0.05, max_speed_mps))


def back_off_command(target: Pose2D, pose: Pose2D, gains: GracefulGains) -> Velocity:
    """Reverse towards ``target`` (a pose facing the dock, behind it) with the graceful law."""
    command = smooth_control_law(target, pose, gains, backward=True)
    return Velocity(command.linear_x_mps, command.angular_z_radps)
