"""One dock_robot request, start to finish: the docking sequence as a pure state machine.

The sequence follows Nav2's opennav_docking ``DockingServer::dockRobot``:

1. pick the dock (by id, by pose, or the nearest; codes 901/902); succeed at once if already charging;
2. back off first if the robot sits right in front of a dock (a restart mid-approach), then
   NAV_TO_STAGING_POSE: the planner takes the robot to the staging pose (903 on failure or after
   ``max_staging_time_s``);
3. INITIAL_PERCEPTION: stand still until ``min_detections`` detections refine the dock pose; without
   them after ``initial_perception_timeout_s`` dock blind on the database pose (or 904);
4. CONTROLLING: the approach controller drives onto the dock (905 after ``approach_timeout_s``);
   charging ends it with success, otherwise arrival hands over to
5. WAIT_FOR_CHARGE: zero command until charging is reported (906 after ``wait_charge_timeout_s``).

A failure in 2-5 is retried (RETRY: stop, back off if at the dock, stage again) up to ``max_retries``
times; then the run fails with the last error. Cancelling commands zero and ends the run. The whole
run is bounded by ``max_docking_time_s`` (907). Obstacles and stale localisation hold the robot with a
zero command while the phase timeouts keep running.
"""

from __future__ import annotations

import enum
import logging
import math
from dataclasses import dataclass, field

from services.docking.approach import GRACEFUL_STAGING_OFFSET_M, dock_frame_error, graceful_staging_pose
from services.docking.approach_control import (
    ARRIVED,
    ApproachController,
    back_off_command,
    back_off_gains,
)
from services.docking.dock_db import DockDatabase
from services.docking.dock_tracker import DockEstimate, DockTracker
from services.docking.errors import DockingError, DockingErrorCode, DockingState, DockNotValidError
from services.docking.graceful import GracefulGains
from services.docking.task_io import STOP, Intent, Navigate, NavOutcome, Outcome, Task, TickInputs
from shared.geometry import Pose2D

log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class DockRequest:
    """What to dock at: ``dock_pose`` (map frame) if given, else ``dock_id``, else the nearest dock."""

    dock_id: str = ""
    dock_pose: Pose2D | None = None
    dock_type: str = ""
    navigate_to_staging_pose: bool = True
    max_staging_time_s: float = 120.0


@dataclass(frozen=True, slots=True)
class DockingConfig:
    """Retries, timeouts and perception settings of a docking run."""

    max_retries: int = 3
    use_detection: bool = True
    allow_blind_docking: bool = True
    #: Wait for detections at staging (the graceful approach); the line approach starts at once.
    wait_for_detection: bool = True
    min_detections: int = 3
    #: Detections taken this soon after arriving at staging are ignored (inputs settle after a move).
    perception_settle_s: float = 0.15
    initial_perception_timeout_s: float = 2.0
    #: Waiting for a robot pose to pick the nearest dock.
    start_timeout_s: float = 5.0
    approach_timeout_s: float = 120.0
    #: Held by an obstacle for this long, the attempt fails (and is retried from staging).
    obstacle_timeout_s: float = 20.0
    wait_charge_timeout_s: float = 5.0
    max_docking_time_s: float = 600.0
    retreat_timeout_s: float = 20.0
    #: Closer than this to a dock pose, facing it, the robot backs off before going to staging.
    retreat_zone_m: float = 0.35
    #: Backing off ends this far from the dock pose (before the planner takes over).
    retreat_clear_m: float = 0.45
    staging_offset_m: float = GRACEFUL_STAGING_OFFSET_M
    #: Without the planner, backing off ends within this distance of the staging pose.
    staging_tolerance_m: float = 0.05
    back_off_gains: GracefulGains = field(default_factory=back_off_gains)


class RunPhase(enum.Enum):
    STARTING = "starting"
    RETREAT = "retreat"
    NAV_TO_STAGING = "nav_to_staging"
    INITIAL_PERCEPTION = "initial_perception"
    CONTROLLING = "controlling"
    WAIT_FOR_CHARGE = "wait_for_charge"
    RETRY = "retry"
    DONE = "done"


_FEEDBACK = {
    RunPhase.STARTING: DockingState.NONE,
    RunPhase.NAV_TO_STAGING: DockingState.NAV_TO_STAGING_POSE,
    RunPhase.INITIAL_PERCEPTION: DockingState.INITIAL_PERCEPTION,
    RunPhase.CONTROLLING: DockingState.CONTROLLING,
    RunPhase.WAIT_FOR_CHARGE: DockingState.WAIT_FOR_CHARGE,
    RunPhase.RETRY: DockingState.RETRY,
}


def facing_dock_closely(robot_pose: Pose2D, dock_pose: Pose2D, zone_m: float) -> bool:
    """The robot is within ``zone_m`` of the dock pose, behind it and facing it (mid-approach or docked)."""
    error = dock_frame_error(robot_pose, dock_pose)
    return robot_pose.distance_to(dock_pose) < zone_m and abs(error.yaw_rad) < math.pi / 2 and error.along_m <= 0.05


class DockingRun(Task[RunPhase]):
    """See the module docstring. ``step`` is called at the approach controller's rate."""

    def __init__(
        self,
        request: DockRequest,
        database: DockDatabase,
        approach: ApproachController,
        config: DockingConfig | None = None,
        tracker: DockTracker | None = None,
    ) -> None:
        super().__init__(RunPhase.STARTING)
        self.request = request
        self.database = database
        self.approach = approach
        self.config = config or DockingConfig()
        self.tracker = tracker or DockTracker()
        self.num_retries = 0
        self.last_error = DockingErrorCode.NONE
        self.dock_id = ""
        self.database_pose: Pose2D | None = None
        self.blind = False
        self.feedback_state = DockingState.NONE
        self._nav_key: object | None = None
        self._retreat_to_staging = False
        self._blocked_since_s: float | None = None

    # --- what the node reads -----------------------------------------------------------------------

    @property
    def retries(self) -> int:
        return self.num_retries

    @property
    def dock_pose(self) -> Pose2D | None:
        """The dock pose the run steers to now: refined by detections when it has them, else the database's."""
        estimate = self.dock_estimate
        if estimate is not None:
            return estimate.pose
        return self.database_pose

    @property
    def dock_estimate(self) -> DockEstimate | None:
        return self.tracker.estimate() if self.config.use_detection else None

    def add_detection(self, dock_in_base: Pose2D, robot_pose_at_stamp: Pose2D, stamp_s: float) -> bool:
        """A detection of the dock (base_link at ``stamp_s``) with the robot's map pose at that time."""
        if not self.config.use_detection or self.done:
            return False
        return self.tracker.add(dock_in_base, robot_pose_at_stamp, stamp_s)

    def docking_time_s(self, now_s: float) -> float:
        return 0.0 if self.started_s is None else now_s - self.started_s

    # --- the state machine -------------------------------------------------------------------------

    def enter(self, phase: RunPhase, now_s: float) -> None:
        super().enter(phase, now_s)
        if phase in _FEEDBACK:
            self.feedback_state = _FEEDBACK[phase]
        elif phase is RunPhase.RETREAT:
            self.feedback_state = DockingState.RETRY if self.num_retries else DockingState.NAV_TO_STAGING_POSE

    def tick(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        assert self.started_s is not None
        if now - self.started_s > self.config.max_docking_time_s:
            return self._fail(DockingErrorCode.TIMEOUT, f"docking took longer than {self.config.max_docking_time_s:g} s")
        handler = {
            RunPhase.STARTING: self._starting,
            RunPhase.RETREAT: self._retreat,
            RunPhase.NAV_TO_STAGING: self._nav_to_staging,
            RunPhase.INITIAL_PERCEPTION: self._initial_perception,
            RunPhase.CONTROLLING: self._controlling,
            RunPhase.WAIT_FOR_CHARGE: self._wait_for_charge,
            RunPhase.RETRY: self._retry,
        }[self.phase]
        return handler(inputs)

    def _starting(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        if inputs.charging:
            return self._succeed("already charging")
        try:
            dock = self._choose_dock(inputs.robot_pose)
        except DockingError as exc:
            return self._fail(exc.error_code, str(exc), retry=False)
        if dock is None:
            if self.phase_time_s(now) > self.config.start_timeout_s:
                return self._fail(DockingErrorCode.TIMEOUT, "no robot pose to choose the nearest dock", retry=False)
            return None
        self.database_pose = dock
        self.tracker.expect(dock)
        log.info("docking at %s (%.2f, %.2f, %.2f)", self.dock_id or "the given pose", dock.x, dock.y, dock.yaw)
        return self._begin_attempt(inputs)

    def _choose_dock(self, robot_pose: Pose2D | None) -> Pose2D | None:
        request = self.request
        if request.dock_pose is not None:
            pose = request.dock_pose
            if not all(math.isfinite(v) for v in pose.as_tuple()):
                raise DockNotValidError(f"dock pose {pose.as_tuple()} is not finite")
            self.dock_id = ""
            return pose
        if request.dock_id:
            dock = self.database.get(request.dock_id)
        elif robot_pose is None:
            if len(self.database) == 1 and not request.dock_type:
                dock = self.database.choose()
            else:
                return None
        else:
            dock = self.database.choose(None, robot_pose, request.dock_type or None)
        self.dock_id = dock.id
        return dock.pose2d

    def _begin_attempt(self, inputs: TickInputs) -> Intent:
        """From wherever the robot is: back off if at the dock, then stage (or perceive, without the planner)."""
        now = inputs.now_s
        dock = self.dock_pose
        assert dock is not None
        near = inputs.robot_pose is not None and facing_dock_closely(inputs.robot_pose, dock, self.config.retreat_zone_m)
        self._retreat_to_staging = not self.request.navigate_to_staging_pose and self.num_retries > 0
        if near or self._retreat_to_staging:
            self.enter(RunPhase.RETREAT, now)
            return STOP
        return self._after_retreat(now)

    def _after_retreat(self, now: float) -> Intent:
        if self.request.navigate_to_staging_pose:
            self._nav_key = self.new_nav_key()
            self.enter(RunPhase.NAV_TO_STAGING, now)
        else:
            self._enter_perception(now)
        return STOP

    def _retreat(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        dock = self.dock_pose
        assert dock is not None
        if self.phase_time_s(now) > self.config.retreat_timeout_s:
            return self._fail(DockingErrorCode.FAILED_TO_CONTROL, "could not back off the dock", retry=False)
        pose = inputs.robot_pose
        if pose is None:
            return self.hold("no robot pose")
        target = graceful_staging_pose(dock, self.config.staging_offset_m)
        if self._retreat_to_staging:
            finished = pose.distance_to(target) <= self.config.staging_tolerance_m
        else:
            finished = pose.distance_to(dock) >= self.config.retreat_clear_m
        if finished:
            return self._after_retreat(now)
        if inputs.blocked_behind:
            return self.hold("obstacle behind")
        return back_off_command(target, pose, self.config.back_off_gains)

    def _nav_to_staging(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        dock = self.dock_pose
        assert self._nav_key is not None and dock is not None
        outcome = inputs.nav.finished(self._nav_key)
        if outcome is None:
            if self.phase_time_s(now) > self.request.max_staging_time_s:
                return self._fail(DockingErrorCode.FAILED_TO_STAGE,
                                  f"staging took longer than {self.request.max_staging_time_s:g} s")
            return Navigate(self.approach.staging_pose(dock), self._nav_key)
        if outcome is NavOutcome.SUCCEEDED:
            self._enter_perception(now)
            return STOP
        reason = inputs.nav.reason or outcome.value
        return self._fail(DockingErrorCode.FAILED_TO_STAGE, f"navigation to the staging pose {outcome.value}: {reason}")

    def _enter_perception(self, now: float) -> None:
        self.tracker.reset(accept_from_s=now + self.config.perception_settle_s)
        self.blind = False
        self.enter(RunPhase.INITIAL_PERCEPTION, now)

    def _initial_perception(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        config = self.config
        estimate = self.dock_estimate
        if not config.use_detection or not config.wait_for_detection:
            return self._start_control(now)
        if estimate is not None and estimate.detections >= config.min_detections:
            return self._start_control(now)
        if self.phase_time_s(now) > config.initial_perception_timeout_s:
            if not config.allow_blind_docking:
                return self._fail(DockingErrorCode.FAILED_TO_DETECT_DOCK,
                                  f"no detection of the dock within {config.initial_perception_timeout_s:g} s")
            self.blind = True
            log.warning("no detection of the dock within %g s: docking on the database pose",
                        config.initial_perception_timeout_s)
            return self._start_control(now)
        return STOP

    def _start_control(self, now: float) -> Intent:
        dock = self.dock_pose
        assert dock is not None
        self.approach.begin(dock)
        self._blocked_since_s = None
        self.enter(RunPhase.CONTROLLING, now)
        return STOP

    def _controlling(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        if inputs.charging:
            return self._succeed("charging")
        if self.phase_time_s(now) > self.config.approach_timeout_s:
            return self._fail(DockingErrorCode.FAILED_TO_CONTROL,
                              f"not on the dock within {self.config.approach_timeout_s:g} s")
        pose = inputs.robot_pose
        if pose is None:
            self.approach.hold()
            return self.hold("no robot pose")
        dock = self.dock_pose
        assert dock is not None
        self.approach.update_dock(dock)
        command = self.approach.command(now, pose, inputs.pose_age_s, inputs.base_twist)
        if command is ARRIVED:
            self.enter(RunPhase.WAIT_FOR_CHARGE, now)
            return STOP
        blocked = inputs.blocked_ahead if command.linear_x_mps > 0.0 else inputs.blocked_behind
        if command.linear_x_mps != 0.0 and blocked:
            self.approach.hold()
            if self._blocked_since_s is None:
                self._blocked_since_s = now
            elif now - self._blocked_since_s > self.config.obstacle_timeout_s:
                return self._fail(DockingErrorCode.FAILED_TO_CONTROL,
                                  f"an obstacle blocked the approach for {self.config.obstacle_timeout_s:g} s")
            return self.hold("obstacle ahead" if command.linear_x_mps > 0.0 else "obstacle behind")
        self._blocked_since_s = None
        return command

    def _wait_for_charge(self, inputs: TickInputs) -> Intent:
        if inputs.charging:
            return self._succeed("charging")
        if self.phase_time_s(inputs.now_s) > self.config.wait_charge_timeout_s:
            return self._fail(DockingErrorCode.FAILED_TO_CHARGE,
                              f"on the dock but not charging after {self.config.wait_charge_timeout_s:g} s")
        return STOP

    def _retry(self, inputs: TickInputs) -> Intent:
        # Hold still until the planner has let go of any goal, then start the next attempt.
        if inputs.nav.busy and self.phase_time_s(inputs.now_s) < self.cancel_timeout_s:
            return STOP
        return self._begin_attempt(inputs)

    # --- endings -----------------------------------------------------------------------------------

    def _succeed(self, message: str) -> Intent:
        self.enter(RunPhase.DONE, self.now_s)
        self.finish(Outcome.SUCCEEDED, DockingErrorCode.NONE, message, self.num_retries)
        return STOP

    def _fail(self, code: DockingErrorCode, message: str, retry: bool = True) -> Intent:
        """An attempt failed: retry while retries remain (and ``retry``), otherwise end the run."""
        self.last_error = code
        self.message = message
        if retry and code is not DockingErrorCode.TIMEOUT and self.num_retries < self.config.max_retries:
            self.num_retries += 1
            log.warning("docking attempt failed (%d %s): %s; retry %d of %d", int(code), code.name, message,
                        self.num_retries, self.config.max_retries)
            self._nav_key = None
            self.enter(RunPhase.RETRY, self.now_s)
            return STOP
        self.enter(RunPhase.DONE, self.now_s)
        log.warning("docking failed (%d %s): %s", int(code), code.name, message)
        self.finish(Outcome.FAILED, code, message, self.num_retries)
        return STOP
