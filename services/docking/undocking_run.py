"""One undock_robot request: back straight out to the staging pose, then confirm charging has stopped.

As Nav2's ``DockingServer::undockRobot``: the dock is the nearest one; the robot reverses with the
graceful law to the staging pose behind it (holding while something is behind it), stops, and the
undock succeeds once battery_status no longer says charging. A robot that is not at a dock (farther
than ``search_radius_m``) and not charging is already undocked. Failing to get clear within the
request's time, or charging that does not stop, is FAILED_TO_CONTROL (905), as in Nav2.
"""

from __future__ import annotations

import enum
import logging
from dataclasses import dataclass, field

from services.docking.approach import GRACEFUL_STAGING_OFFSET_M, graceful_staging_pose
from services.docking.approach_control import back_off_command, back_off_gains
from services.docking.dock_db import DockDatabase
from services.docking.errors import DockingError, DockingErrorCode
from services.docking.graceful import GracefulGains
from services.docking.task_io import STOP, Intent, Outcome, Task, TickInputs
from shared.geometry import Pose2D

log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class UndockConfig:
    staging_offset_m: float = GRACEFUL_STAGING_OFFSET_M
    tolerance_m: float = 0.05
    #: A robot farther than this from every dock is not docked.
    search_radius_m: float = 0.5
    start_timeout_s: float = 5.0
    #: How long charging may take to stop once the robot is off the dock.
    confirm_timeout_s: float = 3.0
    gains: GracefulGains = field(default_factory=back_off_gains)


class UndockPhase(enum.Enum):
    STARTING = "starting"
    BACKING = "backing"
    CONFIRM = "confirm"
    DONE = "done"


class UndockingRun(Task[UndockPhase]):
    """See the module docstring; ``max_undocking_time_s`` bounds the backing-off."""

    def __init__(
        self,
        database: DockDatabase,
        max_undocking_time_s: float = 30.0,
        dock_type: str = "",
        config: UndockConfig | None = None,
    ) -> None:
        super().__init__(UndockPhase.STARTING)
        self.database = database
        self.max_undocking_time_s = max_undocking_time_s
        self.dock_type = dock_type
        self.config = config or UndockConfig()
        self.dock_id = ""
        self.dock_pose: Pose2D | None = None
        self.target: Pose2D | None = None

    watches_obstacles = True

    def state_name(self) -> str:
        return "UNDOCKING"

    def dock_to_excuse(self) -> Pose2D | None:
        return self.dock_pose

    def tick(self, inputs: TickInputs) -> Intent:
        return {
            UndockPhase.STARTING: self._starting,
            UndockPhase.BACKING: self._backing,
            UndockPhase.CONFIRM: self._confirm,
        }[self.phase](inputs)

    def _starting(self, inputs: TickInputs) -> Intent:
        now, pose = inputs.now_s, inputs.robot_pose
        if pose is None:
            if self.phase_time_s(now) > self.config.start_timeout_s:
                return self._end(Outcome.FAILED, DockingErrorCode.TIMEOUT, "no robot pose")
            return None
        try:
            dock = self.database.nearest(pose, self.dock_type or None)
        except DockingError as exc:
            return self._end(Outcome.FAILED, exc.error_code, str(exc))
        if pose.distance_to(dock.pose2d) > self.config.search_radius_m and not inputs.charging:
            return self._end(Outcome.SUCCEEDED, DockingErrorCode.NONE, "not docked")
        self.dock_id, self.dock_pose = dock.id, dock.pose2d
        self.target = graceful_staging_pose(dock.pose2d, self.config.staging_offset_m)
        log.info("undocking from %s to (%.2f, %.2f)", dock.id, self.target.x, self.target.y)
        self.enter(UndockPhase.BACKING, now)
        return STOP

    def _backing(self, inputs: TickInputs) -> Intent:
        now, pose = inputs.now_s, inputs.robot_pose
        assert self.target is not None and self.dock_pose is not None
        if self.phase_time_s(now) > self.max_undocking_time_s:
            return self._end(
                Outcome.FAILED,
                DockingErrorCode.FAILED_TO_CONTROL,
                f"not clear of the dock within {self.max_undocking_time_s:g} s",
            )
        if pose is None:
            return self.hold("no robot pose")
        if inputs.blocked_behind:
            return self.hold("obstacle behind")
        clear = pose.distance_to(self.dock_pose) >= self.config.staging_offset_m - self.config.tolerance_m
        if pose.distance_to(self.target) <= self.config.tolerance_m or clear:
            self.enter(UndockPhase.CONFIRM, now)
            return STOP
        return back_off_command(self.target, pose, self.config.gains)

    def _confirm(self, inputs: TickInputs) -> Intent:
        if not inputs.charging:
            return self._end(Outcome.SUCCEEDED, DockingErrorCode.NONE, "undocked")
        if self.phase_time_s(inputs.now_s) > self.config.confirm_timeout_s:
            return self._end(
                Outcome.FAILED, DockingErrorCode.FAILED_TO_CONTROL, "off the dock but still charging"
            )
        return STOP

    def _end(self, outcome: Outcome, code: DockingErrorCode, message: str) -> Intent:
        self.enter(UndockPhase.DONE, self.now_s)
        self.finish(outcome, code, message)
        return STOP
