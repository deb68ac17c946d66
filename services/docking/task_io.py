"""What a docking-service task sees each tick and what it asks of the robot's base.

Tasks (docking, undocking, patrolling) are pure state machines stepped at the control rate: they get a
:class:`TickInputs` snapshot and return an *intent*: a :class:`Velocity` to publish on ``cmd_vel``, a
:class:`Navigate` request for the planner, or None (drive nothing). They never talk to the bus; the node
builds the inputs and carries out the intents through :class:`~services.docking.drive_arbiter.DriveArbiter`,
which keeps one driver at a time. :class:`Task` holds what every task shares: phases with entry times,
cancellation and the result.

Every task also answers the same questions about itself (its *protocol*), so that the executive
(:mod:`services.docking.executive`) never asks which kind of task runs: its ``docking/state`` name, whether
it is under way (the traffic rule watches robots under way), which dock the obstacle checks excuse, whether
it wants dock detections (and takes them), what it reports to a dock_robot client, what docking request it
would carry on with, and where a patrol stands. The defaults are those of a task that does none of these.
"""

from __future__ import annotations

import abc
import enum
import itertools
from dataclasses import dataclass, field
from typing import Generic, TypeVar

from services.docking.errors import DockingErrorCode, DockingState
from shared.geometry import Pose2D


class NavOutcome(enum.Enum):
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELED = "canceled"


@dataclass(frozen=True, slots=True)
class NavStatus:
    """The planner's last goal as the node knows it: which request it was, running or how it ended."""

    key: object | None = None
    busy: bool = False
    outcome: NavOutcome | None = None
    reason: str = ""

    def finished(self, key: object) -> NavOutcome | None:
        """How the goal sent for ``key`` ended, or None while it runs (or before it was sent)."""
        if key != self.key or self.busy:
            return None
        return self.outcome or NavOutcome.FAILED


@dataclass(frozen=True, slots=True)
class TickInputs:
    """One tick's view of the robot (map frame, node clock)."""

    now_s: float
    #: The latest map pose; None when localisation is stale.
    robot_pose: Pose2D | None = None
    #: How old ``robot_pose`` is (for latency compensation).
    pose_age_s: float = 0.0
    #: Measured body velocity ``(v m/s, w rad/s)`` from odometry, None when unknown.
    base_twist: tuple[float, float] | None = None
    #: battery_status says CHARGING or FULL (and is fresh).
    charging: bool = False
    nav: NavStatus = field(default_factory=NavStatus)
    #: Something that is not the dock is in the robot's way ahead / behind.
    blocked_ahead: bool = False
    blocked_behind: bool = False
    #: The infrared receivers' latest readings ``(right, central, left)`` when fresh, else None.
    ir_dock: tuple[int, int, int] | None = None


@dataclass(frozen=True, slots=True)
class Velocity:
    """Publish this body velocity on cmd_vel."""

    linear_x_mps: float
    angular_z_radps: float

    @property
    def is_zero(self) -> bool:
        return self.linear_x_mps == 0.0 and self.angular_z_radps == 0.0


STOP = Velocity(0.0, 0.0)


@dataclass(frozen=True, slots=True)
class Navigate:
    """Have the planner take the robot to ``pose``; ``key`` names this request (a new key, a new goal)."""

    pose: Pose2D
    key: object


Intent = Velocity | Navigate | None


@dataclass(frozen=True, slots=True)
class DockFeedback:
    """What a docking task reports to its dock_robot client (Nav2's DockRobot feedback, in plain numbers)."""

    state: DockingState
    num_retries: int
    docking_time_s: float


def docking_state_name(state: DockingState) -> str:
    """A docking task's ``docking/state``: its feedback state's name ("STARTING" before the first)."""
    return state.name if state is not DockingState.NONE else "STARTING"


class Outcome(enum.Enum):
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELED = "canceled"


@dataclass(frozen=True, slots=True)
class TaskResult:
    outcome: Outcome
    error_code: DockingErrorCode = DockingErrorCode.NONE
    num_retries: int = 0
    message: str = ""

    @property
    def success(self) -> bool:
        return self.outcome is Outcome.SUCCEEDED


P = TypeVar("P", bound=enum.Enum)
_task_ids = itertools.count(1)


class Task(abc.ABC, Generic[P]):
    """Phases with entry times, a cancel request and a result; subclasses implement :meth:`step`."""

    #: Upper bound on how long a cancel waits for the planner to drop its goal.
    cancel_timeout_s = 3.0

    def __init__(self, first_phase: P) -> None:
        self.task_id = next(_task_ids)
        self.phase: P = first_phase
        self.phase_since_s: float | None = None
        self.started_s: float | None = None
        #: Clock time of the tick being run.
        self.now_s = 0.0
        self.result: TaskResult | None = None
        self.message = ""
        #: Why the task holds the robot still this tick ("" when it does not): for logs and tools.
        self.holding = ""
        self._cancel_requested = False
        self._cancel_since_s: float | None = None
        self._nav_seq = 0

    @property
    def done(self) -> bool:
        return self.result is not None

    def cancel(self) -> None:
        """Ask the task to stop: it commands zero (once the planner has let go) and ends CANCELED."""
        if self.result is None:
            self._cancel_requested = True

    def phase_time_s(self, now_s: float) -> float:
        return 0.0 if self.phase_since_s is None else now_s - self.phase_since_s

    def enter(self, phase: P, now_s: float) -> None:
        self.phase = phase
        self.phase_since_s = now_s

    def hold(self, reason: str) -> Velocity:
        """Hold the robot still this tick, saying why."""
        self.holding = reason
        return STOP

    def new_nav_key(self) -> tuple[int, int]:
        """A key for a new planner request of this task."""
        self._nav_seq += 1
        return (self.task_id, self._nav_seq)

    def finish(
        self,
        outcome: Outcome,
        code: DockingErrorCode = DockingErrorCode.NONE,
        message: str = "",
        num_retries: int = 0,
    ) -> None:
        if self.result is None:
            self.message = message
            self.result = TaskResult(outcome, code, num_retries, message)

    def step(self, inputs: TickInputs) -> Intent:
        """One tick: the intent for the base. Handles the start time and cancellation, then :meth:`tick`."""
        if self.result is not None:
            return None
        now = self.now_s = inputs.now_s
        self.holding = ""
        if self.started_s is None:
            self.started_s = now
            self.phase_since_s = now
        if self._cancel_requested:
            # Command zero; finish once the planner holds no goal (it is asked to drop it), or give up waiting.
            if self._cancel_since_s is None:
                self._cancel_since_s = now
            if not inputs.nav.busy or now - self._cancel_since_s >= self.cancel_timeout_s:
                self.finish(Outcome.CANCELED, DockingErrorCode.NONE, "canceled", self.retries)
            return STOP
        return self.tick(inputs)

    @property
    def retries(self) -> int:
        return 0

    # --- the protocol: what the executive asks of any task (defaults: a task that does none of it) ----

    #: The obstacle checks guard this task's driving (lidar ahead and behind, the sonar ahead) ...
    watches_obstacles = False
    #: ... and only while localisation is fresh (the dock they excuse is placed by the map pose).
    obstacles_need_map_pose = True

    def state_name(self) -> str:
        """The service's ``docking/state`` while this task runs."""
        return type(self).__name__.upper()

    @property
    def under_way(self) -> bool:
        """Driving along the room's ways: the traffic rule looks for robots to give way to."""
        return False

    def dock_to_excuse(self) -> Pose2D | None:
        """The dock (map frame) the obstacle checks must not count as an obstacle, if any."""
        return None

    def wants_detections(self, robot_pose: Pose2D | None) -> bool:
        """Whether dock detections could help now (they cost a rendered and analysed camera frame each)."""
        return False

    def add_detection(self, dock_in_base: Pose2D, robot_pose_at_stamp: Pose2D, stamp_s: float) -> bool:
        """A detection of the dock (base_link at ``stamp_s``) with the robot's map pose then; True if used."""
        return False

    def relocalised(self, correction: Pose2D) -> None:
        """The localiser's map -> odom correction moved by ``correction`` (detections move with odometry)."""

    def dock_feedback(self, now_s: float) -> DockFeedback | None:
        """What to report to a dock_robot client now; None for a task that does not dock."""
        return None

    @property
    def dock_request(self) -> object | None:
        """The docking request to carry on with after an interruption (giving way); None: nothing to resume."""
        return None

    @property
    def waypoint_index(self) -> int | None:
        """The patrol waypoint the robot is heading for, to resume from; None for a task that does not patrol."""
        return None

    @abc.abstractmethod
    def tick(self, inputs: TickInputs) -> Intent:
        """One control period of the task: what to command now (each task defines it)."""
