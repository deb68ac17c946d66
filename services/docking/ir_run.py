"""One dock_robot request docked by infrared alone: :class:`~services.docking.ir_drive.IrDockDrive` until charging.

The docking itself uses no map pose and no camera: it drives on the receivers' readings and odometry's
turn rate from wherever the robot is within the beacon's reach (about 2 m in front of the dock). A robot
that starts out of reach (farther, or beside or behind the dock) is first taken to the dock's staging pose
by the planner, as the robot would be sent home on a real floor; that leg is the only one that uses the
map. The run succeeds when the battery reports charging, fails with FAILED_TO_STAGE (903) when the
planner does, FAILED_TO_DETECT_DOCK (904) when the receivers see nothing for ``max_blind_turns`` turns of
scanning, and TIMEOUT (907) after ``max_time_s``. An obstacle ahead (the lidar's and the sonar's check,
without the dock's exemption since the map pose is not used) turns a drive for the axis into a new scan
and a homing-in from afar into a back-off and a crossing; one behind ends a back-off.
"""

from __future__ import annotations

import enum
import logging
import math

from services.docking.approach import graceful_staging_pose
from services.docking.errors import DockingErrorCode, DockingState
from services.docking.ir_drive import IrDockDrive, IrDriveParams, IrState
from services.docking.task_io import (
    DockFeedback,
    Intent,
    Navigate,
    NavOutcome,
    Outcome,
    Task,
    TickInputs,
    Velocity,
    docking_state_name,
)
from shared.geometry import Pose2D
from shared.world import ROBOT_FRONT_M

log = logging.getLogger(__name__)

#: Readings older than this (sim seconds) count as none: the robot stops rather than drive on old news.
IR_MAX_AGE_S = 0.3
#: Where infrared docking can start without the planner: this far from the dock's face, this far off its axis.
IR_REACH_M = 2.0
IR_REACH_BEARING_RAD = math.radians(45.0)


class IrPhase(enum.Enum):
    NAV_TO_STAGING = "nav_to_staging"
    DOCKING = "docking"
    DONE = "done"


def within_beacon_reach(robot_pose: Pose2D, dock_pose: Pose2D) -> bool:
    """Whether the robot stands where the beacon's fields reach: in front of the dock's face, near its axis."""
    face = dock_pose.compose(Pose2D(ROBOT_FRONT_M, 0.0, math.pi))  # x out of the dock
    local = robot_pose.relative_to(face)
    return (
        local.x > 0.0
        and math.hypot(local.x, local.y) <= IR_REACH_M
        and abs(math.atan2(local.y, local.x)) <= IR_REACH_BEARING_RAD
    )


class IrDockingRun(Task[IrPhase]):
    def __init__(
        self,
        params: IrDriveParams | None = None,
        max_time_s: float = 180.0,
        dock_pose: Pose2D | None = None,
        staging_offset_m: float = 0.7,
        max_staging_time_s: float = 120.0,
    ) -> None:
        super().__init__(IrPhase.DOCKING)
        self.drive = IrDockDrive(params or IrDriveParams())
        self.max_time_s = max_time_s
        #: The dock's map pose, for the planner's leg only (None: the robot is known to be within reach).
        self.dock_pose = dock_pose
        self.staging_offset_m = staging_offset_m
        self.max_staging_time_s = max_staging_time_s
        self._nav_key: object | None = None
        self._began = False
        self.num_retries = 0
        self.feedback_state = DockingState.INITIAL_PERCEPTION
        self._last_tick_s: float | None = None
        self._drive_state: IrState | None = None
        #: How often the drive entered each state: what a run that gives up reports.
        self._entered: dict[str, int] = {}

    def docking_time_s(self, now_s: float) -> float:
        return 0.0 if self.started_s is None else now_s - self.started_s

    @property
    def retries(self) -> int:
        return self.num_retries

    #: The obstacle checks guard the approach, but excuse no dock: without a map pose nothing is the dock.
    watches_obstacles = True
    obstacles_need_map_pose = False

    def state_name(self) -> str:
        return docking_state_name(self.feedback_state)

    def dock_feedback(self, now_s: float) -> DockFeedback:
        return DockFeedback(self.feedback_state, self.num_retries, max(0.0, self.docking_time_s(now_s)))

    def tick(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        assert self.started_s is not None
        dt = 0.0 if self._last_tick_s is None else max(0.0, now - self._last_tick_s)
        self._last_tick_s = now
        if inputs.charging:
            self.enter(IrPhase.DONE, now)
            self.finish(Outcome.SUCCEEDED, message="charging")
            return Velocity(0.0, 0.0)
        if now - self.started_s > self.max_time_s:
            self.finish(
                Outcome.FAILED,
                DockingErrorCode.TIMEOUT,
                f"not charging after {self.max_time_s:.0f} s" + self._story(),
            )
            return Velocity(0.0, 0.0)
        if not self._began:
            self._began = True
            if (
                self.dock_pose is not None
                and inputs.robot_pose is not None
                and not within_beacon_reach(inputs.robot_pose, self.dock_pose)
            ):
                self._nav_key = self.new_nav_key()
                self.enter(IrPhase.NAV_TO_STAGING, now)
                self.feedback_state = DockingState.NAV_TO_STAGING_POSE
        if self.phase is IrPhase.NAV_TO_STAGING:
            return self._nav_to_staging(inputs)
        if inputs.ir_dock is None:
            return self.hold("no fresh infrared readings")
        turned = inputs.base_twist[1] * dt if inputs.base_twist is not None else 0.0
        if inputs.blocked_ahead:
            avoided = self.drive.obstacle_ahead()
            if avoided is not None:
                return Velocity(avoided.linear_mps, avoided.angular_radps)
        command = self.drive.step(inputs.ir_dock, turned, dt)
        if inputs.blocked_behind and command.linear_mps < 0.0:
            command = self.drive.obstacle_behind() or command
        if command.state is not self._drive_state:  # the log tells where a long run spent its time
            log.info(
                "infrared: %s at %.2f s (readings %s)",
                command.state.value,
                self.docking_time_s(now),
                inputs.ir_dock,
            )
            self._drive_state = command.state
            self._entered[command.state.value] = self._entered.get(command.state.value, 0) + 1
        if command.state is IrState.LOST:
            self.finish(
                Outcome.FAILED,
                DockingErrorCode.FAILED_TO_DETECT_DOCK,
                f"no dock beacon seen in {self.drive.params.max_blind_turns:g} turns",
            )
            return Velocity(0.0, 0.0)
        aligned = command.state in (IrState.ALIGNED_FAR, IrState.ALIGNED_NEAR)
        self.feedback_state = DockingState.CONTROLLING if aligned else DockingState.INITIAL_PERCEPTION
        return Velocity(command.linear_mps, command.angular_radps)

    def _story(self) -> str:
        """Why a run gave up, in words: where the drive was and how often it began each state."""
        if not self._entered:
            return " (no infrared readings)" if self.phase is IrPhase.DOCKING else ""
        where = self.drive.state.value
        counts = ", ".join(f"{name} {count}x" for name, count in self._entered.items())
        return f" (in {where}; states begun: {counts})"

    def _nav_to_staging(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        assert self.dock_pose is not None and self._nav_key is not None
        outcome = inputs.nav.finished(self._nav_key)
        if outcome is None:
            if self.phase_time_s(now) > self.max_staging_time_s:
                self.finish(
                    Outcome.FAILED,
                    DockingErrorCode.FAILED_TO_STAGE,
                    f"staging took longer than {self.max_staging_time_s:g} s",
                )
                return Velocity(0.0, 0.0)
            return Navigate(graceful_staging_pose(self.dock_pose, self.staging_offset_m), self._nav_key)
        if outcome is NavOutcome.SUCCEEDED:
            self.enter(IrPhase.DOCKING, now)
            self.feedback_state = DockingState.INITIAL_PERCEPTION
            self._last_tick_s = now
            return Velocity(0.0, 0.0)
        self.finish(
            Outcome.FAILED,
            DockingErrorCode.FAILED_TO_STAGE,
            f"navigation to the staging pose {outcome.value}: {inputs.nav.reason or outcome.value}",
        )
        return Velocity(0.0, 0.0)


__all__ = [
    "IR_MAX_AGE_S",
    "IR_REACH_BEARING_RAD",
    "IR_REACH_M",
    "IrDockingRun",
    "IrPhase",
    "within_beacon_reach",
]
