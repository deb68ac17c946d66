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

Detections are asked for from the staging pose on, as in Nav2 (see :meth:`DockingRun.wants_detections`).
With ``continuous_perception`` (the graceful approach) the dock estimate is kept across phases rather than
started afresh at the staging pose, and with ``handover_distance_m`` the approach takes over as soon as
the robot is near the staging pose, behind the dock and facing it or coming side-on where it can still
curve onto the dock's axis: the planner's goal is cancelled instead of being driven to a standstill
and turned to its heading, INITIAL_PERCEPTION lasts one tick while the planner lets go, and nothing is
driven before it has. The approach then waits for detections as the staging pose would have: with none
in ``initial_perception_timeout_s``, or none before it reaches the dock, it goes on blind on the database
pose, saying so (or fails with 904). An approach that comes up to the plate off the dock's axis backs off
along it and tries again from there, without the planner.

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
    MISALIGNED,
    ApproachController,
    Arrival,
    back_off_command,
    back_off_gains,
)
from services.docking.dock_db import DockDatabase
from services.docking.dock_tracker import DockEstimate, DockTracker
from services.docking.errors import DockingError, DockingErrorCode, DockingState
from services.docking.graceful import GracefulGains
from services.docking.task_io import (
    STOP,
    DockFeedback,
    Intent,
    Navigate,
    NavOutcome,
    Outcome,
    Task,
    TickInputs,
    docking_state_name,
)
from shared.geometry import Pose2D
from shared.world import ROBOT_FRONT_M

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
    #: Keep the detections taken while navigating (the robot pose track places them as consistently as
    #: those taken standing still) instead of perceiving afresh at the staging pose.
    continuous_perception: bool = False
    #: With continuous perception: once the robot is this close to the staging pose, at least
    #: ``handover_min_back_m`` behind the dock, heading within ``handover_yaw_rad`` of the dock's heading,
    #: with the dock within ``handover_bearing_rad`` of its own, and where the approach would set off on a
    #: curve rather than turn on the spot (``ApproachController.curves_in_from``), the approach controller
    #: takes over from navigation (which is cancelled) instead of waiting for it to stop and turn at the
    #: staging pose; detections refine the dock pose as they come. None: navigation finishes first.
    handover_distance_m: float | None = None
    handover_min_back_m: float = 0.45
    #: A robot coming side-on (up to 1.6 rad off the dock's heading) is taken over while it can still curve
    #: onto the axis at speed, rather than stopped at the staging pose to turn on the spot (measurement 77).
    handover_yaw_rad: float = 1.6
    handover_bearing_rad: float = 1.2
    #: This close to the staging pose any heading will do: the approach turns on the spot, as navigation
    #: would before it could stop there.
    handover_any_heading_m: float = 0.15
    #: The dock is "in view" while the newest accepted detection is at most this old.
    detection_fresh_s: float = 0.5
    #: While controlling, a robot pose older than this (a late control tick) holds the robot rather than
    #: steer it by where it was; None: any pose the node passes on is used.
    max_control_pose_age_s: float | None = None
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
    #: After an approach came up to the plate askew, the robot backs off this far from the dock pose and
    #: approaches again from there, without the planner.
    realign_clear_m: float = 0.6
    staging_offset_m: float = GRACEFUL_STAGING_OFFSET_M
    #: Without the planner, backing off ends within this distance of the staging pose.
    staging_tolerance_m: float = 0.05
    back_off_gains: GracefulGains = field(default_factory=back_off_gains)


#: Where a dock's marker could be in a forward camera's view: its range, its bearing from the robot's
#: heading within the camera's 70 degree field of view less the marker's own width, and the marker seen at
#: most this far off its normal (it faces back along the dock's axis, towards the staging pose, and is not
#: seen from behind the dock). Past this bearing the marker is rarely found, mostly while the robot turns
#: onto the dock at the staging pose with its camera side-on (measurement 66).
DETECTION_VIEW_RANGE_M = 3.5
DETECTION_VIEW_BEARING_RAD = math.radians(30.0)
DETECTION_VIEW_OFF_NORMAL_RAD = math.radians(80.0)
#: Closer than this behind the dock pose the forward camera no longer holds the whole marker: the last
#: stretch of the approach goes on the estimate it has (rendered frames of the shipped dock, along its axis:
#: found from 0.10 m, not at 0.05 m).
DETECTION_BLIND_M = 0.12


def marker_in_view(robot_pose: Pose2D, dock: Pose2D) -> bool:
    """Whether the marker of the dock at ``dock`` (the docked base_link pose) could be in the forward
    camera's view from ``robot_pose``: see ``DETECTION_VIEW_*``."""
    marker = dock.compose(Pose2D(ROBOT_FRONT_M, 0.0, 0.0))
    seen = marker.relative_to(robot_pose)
    if (
        math.hypot(seen.x, seen.y) >= DETECTION_VIEW_RANGE_M
        or abs(math.atan2(seen.y, seen.x)) >= DETECTION_VIEW_BEARING_RAD
    ):
        return False
    robot = robot_pose.relative_to(dock)  # in front of the marker: behind the dock's origin, along its axis
    return robot.x < 0.0 and math.atan2(abs(robot.y), -robot.x) < DETECTION_VIEW_OFF_NORMAL_RAD


class RunPhase(enum.Enum):
    STARTING = "starting"
    RETREAT = "retreat"
    NAV_TO_STAGING = "nav_to_staging"
    INITIAL_PERCEPTION = "initial_perception"
    CONTROLLING = "controlling"
    WAIT_FOR_CHARGE = "wait_for_charge"
    RETRY = "retry"
    DONE = "done"


#: The phases that use detections: from the staging pose on, as in Nav2's docking server.
_SEEKS_DETECTIONS = (RunPhase.INITIAL_PERCEPTION, RunPhase.CONTROLLING)

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
    return (
        robot_pose.distance_to(dock_pose) < zone_m
        and abs(error.yaw_rad) < math.pi / 2
        and error.along_m <= 0.05
    )


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
        self._realign = False
        self._handed_over = False
        #: Handed over with the dock out of view: since when the approach has steered on the database pose.
        self._unseen_since_s: float | None = None
        self._blocked_since_s: float | None = None
        self._last_pose: Pose2D | None = None

    # --- what the node reads -----------------------------------------------------------------------

    @property
    def retries(self) -> int:
        return self.num_retries

    watches_obstacles = True

    def state_name(self) -> str:
        return docking_state_name(self.feedback_state)

    @property
    def under_way(self) -> bool:
        return self.phase is RunPhase.NAV_TO_STAGING

    def dock_to_excuse(self) -> Pose2D | None:
        return self.dock_pose

    def dock_feedback(self, now_s: float) -> DockFeedback:
        return DockFeedback(self.feedback_state, self.num_retries, max(0.0, self.docking_time_s(now_s)))

    @property
    def dock_request(self) -> DockRequest:
        return self.request

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

    def relocalised(self, correction: Pose2D) -> None:
        """The localiser's map -> odom correction moved by ``correction``: detections move with odometry."""
        self.tracker.shift(correction)

    def wants_detections(self, robot_pose: Pose2D | None) -> bool:
        """Whether detections could help now: from staging on, while the dock's marker could be in view.

        Detections cost a rendered and analysed camera frame each, so the run asks for them as Nav2's
        docking server does, from the staging pose on (INITIAL_PERCEPTION and CONTROLLING), and there
        only while the marker is within ``DETECTION_VIEW_RANGE_M`` and ``DETECTION_VIEW_BEARING_RAD`` of
        the robot's heading, the robot in front of it (not while it turns onto the dock at the staging
        pose), until the camera is too close to hold the marker (``DETECTION_BLIND_M``). Without a pose
        yet it looks anyway. Not on the way: frames taken there were most of all frames, and dockings
        without them were as quick and as precise (measurement 66; far detections are the least precise,
        and the approach refines the dock pose from the staging pose).
        """
        if not self.config.use_detection or self.done or self.phase not in _SEEKS_DETECTIONS:
            return False
        dock = self.dock_pose
        if robot_pose is None or dock is None:
            return True
        if robot_pose.relative_to(dock).x >= -DETECTION_BLIND_M:
            return False
        return marker_in_view(robot_pose, dock)

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
            return self._fail(
                DockingErrorCode.TIMEOUT, f"docking took longer than {self.config.max_docking_time_s:g} s"
            )
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
                return self._fail(
                    DockingErrorCode.TIMEOUT, "no robot pose to choose the nearest dock", retry=False
                )
            return None
        if inputs.robot_pose is None and self.phase_time_s(now) <= self.config.start_timeout_s:
            return None  # where the robot is decides the first move (backing off the dock, or staging)
        self.database_pose = dock
        self.tracker.expect(dock)
        log.info(
            "docking at %s (%.2f, %.2f, %.2f)", self.dock_id or "the given pose", dock.x, dock.y, dock.yaw
        )
        return self._begin_attempt(inputs)

    def _choose_dock(self, robot_pose: Pose2D | None) -> Pose2D | None:
        request = self.request
        if request.dock_pose is not None:
            pose = request.dock_pose
            if not all(math.isfinite(v) for v in pose.as_tuple()):
                raise DockingError(
                    DockingErrorCode.DOCK_NOT_VALID, f"dock pose {pose.as_tuple()} is not finite"
                )
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
        if self.num_retries > 0 and self.config.continuous_perception:
            self.tracker.reset()  # the attempt failed: perceive afresh
        dock = self.dock_pose
        assert dock is not None
        near = inputs.robot_pose is not None and facing_dock_closely(
            inputs.robot_pose, dock, self.config.retreat_zone_m
        )
        self._realign = self._realign and near
        self._retreat_to_staging = (
            not self.request.navigate_to_staging_pose and self.num_retries > 0 and not self._realign
        )
        if near or self._retreat_to_staging:
            self.enter(RunPhase.RETREAT, now)
            return STOP
        return self._after_retreat(inputs)

    def _after_retreat(self, inputs: TickInputs) -> Intent:
        if self.request.navigate_to_staging_pose and not self._realign:
            self._nav_key = self.new_nav_key()
            self.enter(RunPhase.NAV_TO_STAGING, inputs.now_s)
            return self._nav_to_staging(inputs)  # the goal goes out on this tick, not the next
        self._enter_perception(inputs.now_s)
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
        elif self._realign:
            finished = pose.distance_to(dock) >= self.config.realign_clear_m
        else:
            finished = pose.distance_to(dock) >= self.config.retreat_clear_m
        if finished:
            return self._after_retreat(inputs)
        if inputs.blocked_behind:
            return self.hold("obstacle behind")
        return back_off_command(target, pose, self.config.back_off_gains)

    def _nav_to_staging(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        dock = self.dock_pose
        assert self._nav_key is not None and dock is not None
        outcome = inputs.nav.finished(self._nav_key)
        if outcome is None:
            if self._ready_to_hand_over(inputs):
                assert inputs.robot_pose is not None
                log.info(
                    "handing over from navigation to the approach %.2f m from the staging pose",
                    inputs.robot_pose.distance_to(self.approach.staging_pose(dock)),
                )
                # One tick of perception (the planner is asked to let go meanwhile), then the approach
                # starts on whatever dock pose there is: detections refine it on the way in.
                self._handed_over = True
                self._enter_perception(now)
                return STOP
            if self.phase_time_s(now) > self.request.max_staging_time_s:
                return self._fail(
                    DockingErrorCode.FAILED_TO_STAGE,
                    f"staging took longer than {self.request.max_staging_time_s:g} s",
                )
            return Navigate(self.approach.staging_pose(dock), self._nav_key)
        if outcome is NavOutcome.SUCCEEDED:
            self._enter_perception(now)
            return STOP
        reason = inputs.nav.reason or outcome.value
        return self._fail(
            DockingErrorCode.FAILED_TO_STAGE, f"navigation to the staging pose {outcome.value}: {reason}"
        )

    def _ready_to_hand_over(self, inputs: TickInputs) -> bool:
        """Close to the staging pose, behind the dock, facing it or side-on where the approach curves in from:
        see ``handover_distance_m``."""
        config = self.config
        pose = inputs.robot_pose
        if config.handover_distance_m is None or not config.continuous_perception or pose is None:
            return False
        dock = self.dock_pose
        assert dock is not None
        to_staging_m = pose.distance_to(self.approach.staging_pose(dock))
        if to_staging_m > config.handover_distance_m:
            return False
        if to_staging_m <= config.handover_any_heading_m:
            return True
        error = dock_frame_error(pose, dock)
        if error.along_m > -config.handover_min_back_m or abs(error.yaw_rad) > config.handover_yaw_rad:
            return False
        dock_in_base = dock.relative_to(pose)
        if abs(math.atan2(dock_in_base.y, dock_in_base.x)) > config.handover_bearing_rad:
            return False
        return self.approach.curves_in_from(pose, dock)

    def _dock_in_view(self, now: float) -> bool:
        """Enough detections, the newest of them recent."""
        estimate = self.dock_estimate
        return (
            estimate is not None
            and estimate.detections >= self.config.min_detections
            and now - estimate.stamp_s <= self.config.detection_fresh_s
        )

    def _enter_perception(self, now: float) -> None:
        if not self.config.continuous_perception:
            self.tracker.reset(accept_from_s=now + self.config.perception_settle_s)
        self.blind = False
        self.enter(RunPhase.INITIAL_PERCEPTION, now)

    def _initial_perception(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        config = self.config
        estimate = self.dock_estimate
        if not config.use_detection or not config.wait_for_detection or self._handed_over:
            return self._start_control(now)
        if config.continuous_perception:
            if self._dock_in_view(now):
                return self._start_control(now)
        elif estimate is not None and estimate.detections >= config.min_detections:
            return self._start_control(now)
        if self.phase_time_s(now) > config.initial_perception_timeout_s:
            if not config.allow_blind_docking:
                return self._fail(
                    DockingErrorCode.FAILED_TO_DETECT_DOCK,
                    f"no detection of the dock within {config.initial_perception_timeout_s:g} s",
                )
            self.blind = True
            log.warning(
                "no detection of the dock within %g s: docking on the database pose",
                config.initial_perception_timeout_s,
            )
            return self._start_control(now)
        return STOP

    def _start_control(self, now: float) -> Intent:
        config = self.config
        in_view = self._dock_in_view(now)
        if config.continuous_perception and not in_view:
            # Detections from long ago (placed with whatever the localiser said then): steer on the
            # database pose until the dock comes into view again.
            self.tracker.reset()
        # A handover skips the wait for detections; the approach then gives them as long to come.
        waits = config.use_detection and config.wait_for_detection
        self._unseen_since_s = now if self._handed_over and waits and not in_view else None
        dock = self.dock_pose
        assert dock is not None
        self.approach.begin(dock)
        self._realign = False
        self._handed_over = False
        self._blocked_since_s = None
        self.enter(RunPhase.CONTROLLING, now)
        return STOP

    def _controlling(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        if inputs.charging:
            if self._unseen_since_s is not None and not self._dock_in_view(now):
                self._went_blind("since taking over from navigation")  # on the plate all the same
            self._log_believed_error(now)
            return self._succeed("charging")
        if self.phase_time_s(now) > self.config.approach_timeout_s:
            return self._fail(
                DockingErrorCode.FAILED_TO_CONTROL,
                f"not on the dock within {self.config.approach_timeout_s:g} s",
            )
        if self._unseen_since_s is not None and (failed := self._still_unseen(now, arrived=False)):
            return failed
        if inputs.nav.busy:
            # Handed over while navigating: nothing is published until the planner has let go.
            self.approach.hold()
            return self.hold("waiting for navigation to let go")
        pose = inputs.robot_pose
        if pose is None:
            self.approach.hold()
            return self.hold("no robot pose")
        limit = self.config.max_control_pose_age_s
        if limit is not None and inputs.pose_age_s > limit:
            self.approach.hold()
            return self.hold("robot pose too old to steer by")
        self._last_pose = pose
        dock = self.dock_pose
        assert dock is not None
        self.approach.update_dock(dock)
        command = self.approach.command(now, pose, inputs.pose_age_s, inputs.base_twist)
        if log.isEnabledFor(logging.DEBUG):
            error = dock_frame_error(pose, dock)
            log.debug(
                "approach t=%.3f along=%.3f lateral=%.4f yaw=%.4f age=%.3f twist=%s -> %s",
                now,
                error.along_m,
                error.lateral_m,
                error.yaw_rad,
                inputs.pose_age_s,
                inputs.base_twist,
                command,
            )
        if isinstance(command, Arrival):
            if command is MISALIGNED:
                self._realign = True
                return self._fail(
                    DockingErrorCode.FAILED_TO_CONTROL,
                    "came up to the plate off its axis: backing off to approach again",
                )
            if self._unseen_since_s is not None and (failed := self._still_unseen(now, arrived=True)):
                return failed
            self.enter(RunPhase.WAIT_FOR_CHARGE, now)
            return STOP
        blocked = inputs.blocked_ahead if command.linear_x_mps > 0.0 else inputs.blocked_behind
        if command.linear_x_mps != 0.0 and blocked:
            self.approach.hold()
            if self._blocked_since_s is None:
                self._blocked_since_s = now
            elif now - self._blocked_since_s > self.config.obstacle_timeout_s:
                return self._fail(
                    DockingErrorCode.FAILED_TO_CONTROL,
                    f"an obstacle blocked the approach for {self.config.obstacle_timeout_s:g} s",
                )
            return self.hold("obstacle ahead" if command.linear_x_mps > 0.0 else "obstacle behind")
        self._blocked_since_s = None
        return command

    def _still_unseen(self, now: float, arrived: bool) -> Intent | None:
        """After a handover with the dock out of view: once it comes into view, nothing to say; without it
        for ``initial_perception_timeout_s``, or all the way to the dock, what the wait at the staging pose
        would have done: fail with 904, or go on blind on the database pose, saying so."""
        assert self._unseen_since_s is not None
        config = self.config
        if self._dock_in_view(now):
            self._unseen_since_s = None
            return None
        if arrived:
            when = "since taking over from navigation"
        elif now - self._unseen_since_s > config.initial_perception_timeout_s:
            when = f"within {config.initial_perception_timeout_s:g} s of taking over from navigation"
        else:
            return None
        if not config.allow_blind_docking:
            self._unseen_since_s = None
            return self._fail(DockingErrorCode.FAILED_TO_DETECT_DOCK, f"no detection of the dock {when}")
        self._went_blind(when)
        return None

    def _went_blind(self, when: str) -> None:
        self._unseen_since_s = None
        self.blind = True
        log.warning("no detection of the dock %s: docking on the database pose", when)

    def _log_believed_error(self, now: float) -> None:
        """Where the robot believes it stands against the dock as charging begins (judged on truth elsewhere)."""
        dock = self.dock_pose
        if self._last_pose is None or dock is None:
            return
        error = dock_frame_error(self._last_pose, dock)
        log.info(
            "charging after %.2f s of approach; believed offset from the dock: along %.1f mm, lateral %.1f mm, "
            "yaw %.2f deg",
            self.phase_time_s(now),
            1000.0 * error.along_m,
            1000.0 * error.lateral_m,
            math.degrees(error.yaw_rad),
        )

    def _wait_for_charge(self, inputs: TickInputs) -> Intent:
        if inputs.charging:
            return self._succeed("charging")
        if self.phase_time_s(inputs.now_s) > self.config.wait_charge_timeout_s:
            return self._fail(
                DockingErrorCode.FAILED_TO_CHARGE,
                f"on the dock but not charging after {self.config.wait_charge_timeout_s:g} s",
            )
        return STOP

    def _retry(self, inputs: TickInputs) -> Intent:
        # Hold still until the planner has let go of any goal, then start the next attempt.
        if inputs.nav.busy and self.phase_time_s(inputs.now_s) < self.cancel_timeout_s:
            return STOP
        if inputs.robot_pose is None and self.phase_time_s(inputs.now_s) < self.config.start_timeout_s:
            return self.hold("no robot pose")  # it decides whether to back off the dock first
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
            log.warning(
                "docking attempt failed (%d %s): %s; retry %d of %d",
                int(code),
                code.name,
                message,
                self.num_retries,
                self.config.max_retries,
            )
            self._nav_key = None
            self.enter(RunPhase.RETRY, self.now_s)
            return STOP
        self.enter(RunPhase.DONE, self.now_s)
        log.warning("docking failed (%d %s): %s", int(code), code.name, message)
        self.finish(Outcome.FAILED, code, message, self.num_retries)
        return STOP
