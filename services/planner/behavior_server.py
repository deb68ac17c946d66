"""The planner's stand-in for Nav2's behavior_server (``spin``, ``backup``, ``drive_on_heading``, ``wait``)
and for its controller_server's ``follow_path`` (:mod:`services.planner.path_following`).

One behaviour runs at a time: a new behaviour goal of any kind ends the one running (CANCELED). Navigation
comes first: a behaviour goal is refused while a ``navigate_to_pose`` goal runs, and a navigation goal ends
a running behaviour, so that a user's forgotten ``wait`` can never hold up zendock's own docking. The
motions themselves (:mod:`services.planner.behaviors`) check the costmap ahead every control cycle.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from services.planner.behaviors import BehaviorParams, DriveStraight, Outcome, Spin, Step, Wait
from services.planner.goal_check import ACCEPTED_FRAMES
from services.planner.navigation_run import NavSnapshot
from services.planner.path_following import FollowPath
from shared import topics
from shared.action import ActionServer, ServerGoalHandle
from shared.geometry import yaw_from_quaternion
from shared.interface_types import ActionType
from shared.interfaces.behaviors import (
    ASSISTED_TELEOP,
    BACK_UP,
    DRIVE_ON_HEADING,
    SPIN,
    WAIT,
    AssistedTeleopErrorCode,
    AssistedTeleopGoal,
    BackUpErrorCode,
    BackUpFeedback,
    BackUpGoal,
    DriveOnHeadingErrorCode,
    DriveOnHeadingFeedback,
    DriveOnHeadingGoal,
    SpinErrorCode,
    SpinFeedback,
    SpinGoal,
    WaitFeedback,
    WaitGoal,
)
from shared.interfaces.navigation import (
    FOLLOW_PATH,
    FollowPathErrorCode,
    FollowPathFeedback,
    FollowPathGoal,
)
from shared.messages import Duration
from shared.node import Node

Behavior = Spin | DriveStraight | Wait | FollowPath


@dataclass(frozen=True)
class _Codes:
    """An action's Nav2 error codes for each way a behaviour ends badly."""

    unknown: int
    timeout: int
    tf_error: int
    collision_ahead: int
    invalid_input: int
    no_progress: int = 0


_SPIN_CODES = _Codes(
    SpinErrorCode.UNKNOWN,
    SpinErrorCode.TIMEOUT,
    SpinErrorCode.TF_ERROR,
    SpinErrorCode.COLLISION_AHEAD,
    SpinErrorCode.UNKNOWN,  # Spin has no INVALID_INPUT: every yaw is a valid turn
)
_BACK_UP_CODES = _Codes(
    BackUpErrorCode.UNKNOWN,
    BackUpErrorCode.TIMEOUT,
    BackUpErrorCode.TF_ERROR,
    BackUpErrorCode.COLLISION_AHEAD,
    BackUpErrorCode.INVALID_INPUT,
)
_DRIVE_CODES = _Codes(
    DriveOnHeadingErrorCode.UNKNOWN,
    DriveOnHeadingErrorCode.TIMEOUT,
    DriveOnHeadingErrorCode.TF_ERROR,
    DriveOnHeadingErrorCode.COLLISION_AHEAD,
    DriveOnHeadingErrorCode.INVALID_INPUT,
)
_WAIT_CODES = _Codes(0, 0, 0, 0, 0)  # Wait's result has error_code and error_msg but names no codes
_FOLLOW_CODES = _Codes(
    FollowPathErrorCode.UNKNOWN,
    FollowPathErrorCode.CONTROLLER_TIMED_OUT,
    FollowPathErrorCode.TF_ERROR,
    FollowPathErrorCode.NO_VALID_CONTROL,
    FollowPathErrorCode.INVALID_PATH,
    FollowPathErrorCode.FAILED_TO_MAKE_PROGRESS,
)
#: The controller_id a script may name: Nav2's default controller plugin's, or none.
CONTROLLER_IDS = ("", "FollowPath")


class _Running:
    """The behaviour running now: its goal, its motion and how to report on it."""

    def __init__(
        self,
        handle: ServerGoalHandle[Any, Any, Any],
        action: ActionType[Any, Any, Any],
        motion: Behavior,
        codes: _Codes,
        feedback: Callable[[Step], Any],
        started_s: float,
    ) -> None:
        self.handle = handle
        self.action = action
        self.motion = motion
        self.codes = codes
        self.feedback = feedback
        self.started_s = started_s

    def result(self, now_s: float, code: int = 0, message: str = "") -> Any:
        return _result(self.action, now_s - self.started_s, code, message)


def _result(action: ActionType[Any, Any, Any], elapsed_s: float, code: int = 0, message: str = "") -> Any:
    if action is FOLLOW_PATH:  # its result carries no elapsed time
        return action.result(error_code=int(code), error_msg=message)
    elapsed = Duration.from_sec(max(0.0, elapsed_s))
    return action.result(total_elapsed_time=elapsed, error_code=int(code), error_msg=message)


def _seconds(duration: Duration) -> float:
    return duration.to_sec()


class BehaviorServer:
    """Serves the four behaviours on ``node``; :meth:`tick` steps the running one each control cycle."""

    def __init__(
        self,
        node: Node,
        params: BehaviorParams,
        *,
        publish_cmd: Callable[[float, float], None],
        navigating: Callable[[], bool],
        follow_path: Callable[[np.ndarray], FollowPath],
    ) -> None:
        """``follow_path(poses)``: a :class:`FollowPath` with the planner's controller and limits."""
        self._node = node
        self._log = node.log
        self._params = params
        self._publish_cmd = publish_cmd
        self._navigating = navigating
        self._follow_path = follow_path
        self._running: _Running | None = None
        self._servers = [
            self._serve(SPIN, topics.SPIN),
            self._serve(BACK_UP, topics.BACKUP),
            self._serve(DRIVE_ON_HEADING, topics.DRIVE_ON_HEADING),
            self._serve(WAIT, topics.WAIT),
            self._serve(FOLLOW_PATH, topics.FOLLOW_PATH),
            self._serve(ASSISTED_TELEOP, topics.ASSISTED_TELEOP),
        ]

    def _serve(self, action: ActionType[Any, Any, Any], name: str) -> ActionServer[Any, Any, Any]:
        return ActionServer(
            self._node,
            action,
            name,
            on_goal=self._on_goal,
            on_accepted=lambda handle: self._on_accepted(action, handle),
            on_cancel=self._on_cancel,
            preempt_result=lambda: _result(action, 0.0, 0, "preempted by a newer goal"),
        )

    @property
    def active(self) -> bool:
        return self._running is not None

    # --- goals --------------------------------------------------------------------------------------

    def _on_goal(self, goal: Any) -> None:
        """Refuse a behaviour while navigating: the ``ValueError``'s text is the client's reason."""
        if self._navigating():
            raise ValueError("navigate_to_pose is running: cancel it before a behaviour")

    def _on_accepted(
        self, action: ActionType[Any, Any, Any], handle: ServerGoalHandle[Any, Any, Any]
    ) -> None:
        if not handle.active:
            return  # preempted before it started
        now = self._node.now()
        if self._running is not None and self._running.handle is not handle:
            self._end(
                self._running, now, Outcome.RUNNING, f"preempted by a {action.type_name} goal", cancel=True
            )
        handle.execute()
        try:
            motion, codes, feedback = self._motion_for(handle.goal)
        except ValueError as exc:  # Nav2 accepts such a goal and aborts it with INVALID_INPUT
            codes = {BackUpGoal: _BACK_UP_CODES, FollowPathGoal: _FOLLOW_CODES}.get(
                type(handle.goal), _DRIVE_CODES
            )
            code: int
            if isinstance(exc, _InvalidController):
                code = FollowPathErrorCode.INVALID_CONTROLLER
            elif isinstance(exc, _NotServed):
                code = AssistedTeleopErrorCode.UNKNOWN
            else:
                code = codes.invalid_input
            self._log.info("%s aborted: %s", action.type_name, exc)
            handle.abort(_result(action, 0.0, code, str(exc)))
            return
        self._running = _Running(handle, action, motion, codes, feedback, now)
        self._log.info("%s started", action.type_name.rsplit("/", 1)[-1])

    def _motion_for(self, goal: Any) -> tuple[Behavior, _Codes, Callable[[Step], Any]]:
        p = self._params
        if isinstance(goal, SpinGoal):
            spin = Spin(goal.target_yaw, _seconds(goal.time_allowance), p)
            return spin, _SPIN_CODES, lambda step: SpinFeedback(angular_distance_traveled=step.progress)
        if isinstance(goal, BackUpGoal):
            _only_x(goal.target.y, goal.target.z)
            drive = DriveStraight(abs(goal.target.x), -abs(goal.speed), _seconds(goal.time_allowance), p)
            return drive, _BACK_UP_CODES, lambda step: BackUpFeedback(distance_traveled=step.progress)
        if isinstance(goal, DriveOnHeadingGoal):
            _only_x(goal.target.y, goal.target.z)
            if goal.target.x * goal.speed < 0.0:
                raise ValueError(
                    f"target.x ({goal.target.x:g}) and speed ({goal.speed:g}) must have the same sign"
                )
            drive = DriveStraight(abs(goal.target.x), goal.speed, _seconds(goal.time_allowance), p)
            return drive, _DRIVE_CODES, lambda step: DriveOnHeadingFeedback(distance_traveled=step.progress)
        if isinstance(goal, AssistedTeleopGoal):
            raise _NotServed(ASSISTED_TELEOP_REFUSAL)
        if isinstance(goal, FollowPathGoal):
            follow = self._follow_path(_path_poses(goal))
            return (
                follow,
                _FOLLOW_CODES,
                lambda step: FollowPathFeedback(
                    distance_to_goal=step.progress, speed=step.cmd[0] if step.cmd is not None else 0.0
                ),
            )
        assert isinstance(goal, WaitGoal)
        return (
            Wait(_seconds(goal.time)),
            _WAIT_CODES,
            lambda step: WaitFeedback(time_left=Duration.from_sec(max(0.0, step.progress))),
        )

    def _on_cancel(self, handle: ServerGoalHandle[Any, Any, Any]) -> None:
        running = self._running
        if running is not None and running.handle is handle:
            self._end(running, self._node.now(), Outcome.RUNNING, "canceled on request", cancel=True)
        elif handle.active:
            handle.canceled(_result(handle.action, 0.0, 0, "canceled on request"))

    def preempt(self, why: str) -> None:
        """End the running behaviour (a navigation goal takes the robot)."""
        if self._running is not None:
            self._end(self._running, self._node.now(), Outcome.RUNNING, why, cancel=True)

    # --- stepping -----------------------------------------------------------------------------------

    def tick(self, snap: NavSnapshot) -> None:
        running = self._running
        if running is None:
            return
        if not running.handle.active:  # ended elsewhere (preempted within its own server)
            self._running = None
            return
        now = snap.now_s
        motion = running.motion
        step = motion.step(snap) if isinstance(motion, FollowPath) else motion.step(snap.pose, now, snap.grid)
        if step.outcome is Outcome.RUNNING:
            if step.cmd is not None:
                self._publish_cmd(*step.cmd)
            running.handle.publish_feedback(running.feedback(step))
            return
        self._end(running, now, step.outcome, step.reason)

    def _end(
        self, running: _Running, now: float, outcome: Outcome, why: str, *, cancel: bool = False
    ) -> None:
        self._running = None
        if not isinstance(running.motion, Wait):
            self._publish_cmd(0.0, 0.0)
        name = running.action.type_name.rsplit("/", 1)[-1]
        handle = running.handle
        if not handle.active:
            return
        if cancel:
            self._log.info("%s ended: %s", name, why)
            handle.canceled(running.result(now, 0, why))
        elif outcome is Outcome.SUCCEEDED:
            self._log.info("%s succeeded", name)
            handle.succeed(running.result(now))
        else:
            code = {
                Outcome.TIMED_OUT: running.codes.timeout,
                Outcome.COLLISION_AHEAD: running.codes.collision_ahead,
                Outcome.NO_POSE: running.codes.tf_error,
                Outcome.NO_PROGRESS: running.codes.no_progress,
            }.get(outcome, running.codes.unknown)
            self._log.info("%s aborted (%d): %s", name, code, why)
            handle.abort(running.result(now, code, why))

    def close(self) -> None:
        self.preempt("the planner is shutting down")
        for server in self._servers:
            server.close()


def _only_x(y: float, z: float) -> None:
    if y != 0.0 or z != 0.0:
        raise ValueError(f"only target.x is driven; target.y ({y:g}) and target.z ({z:g}) must be 0")


def _path_poses(goal: FollowPathGoal) -> np.ndarray:
    """The goal's path as ``(N, 3)`` map poses; ``ValueError`` (INVALID_PATH / INVALID_CONTROLLER) naming
    what is wrong."""
    if goal.controller_id not in CONTROLLER_IDS:
        raise _InvalidController(
            f"controller_id {goal.controller_id!r} is not one of zendock's ({', '.join(map(repr, CONTROLLER_IDS))})"
        )
    if not goal.path.poses:
        raise ValueError("an empty path")
    frames = {p.header.frame_id.strip().lstrip("/") for p in goal.path.poses}
    frames.add(goal.path.header.frame_id.strip().lstrip("/"))
    if not frames <= set(ACCEPTED_FRAMES):
        raise ValueError(f"the path is not in the map frame: {sorted(frames)}")
    poses = np.array(
        [
            (
                p.pose.position.x,
                p.pose.position.y,
                yaw_from_quaternion(
                    p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z, p.pose.orientation.w
                ),
            )
            for p in goal.path.poses
        ],
        dtype=float,
    )
    if not np.isfinite(poses).all():
        raise ValueError("the path has a pose that is not finite")
    return poses


class _InvalidController(ValueError):
    """A controller_id zendock does not have (Nav2's INVALID_CONTROLLER)."""


class _NotServed(ValueError):
    """A behaviour zendock answers only to refuse, with the reason as ``error_msg``."""


#: Why ``assisted_teleop`` is refused: it filters a second velocity topic (``cmd_vel_teleop``) that
#: zendock does not carry; its collision-checked motions are the behaviours above.
ASSISTED_TELEOP_REFUSAL = (
    "assisted_teleop is not served by zendock: publish Twist on cmd_vel to drive, or use spin, backup "
    "or drive_on_heading for a motion checked against the costmap"
)
