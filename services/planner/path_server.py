"""The planner's stand-in for Nav2's planner_server and smoother_server: ``compute_path_to_pose`` and
``compute_path_through_poses`` answer with a path, and nothing drives it; ``smooth_path`` smooths a given
one.

The paths come from the same A* and smoothing as navigation's, on the current costmap, on a worker
thread of their own (a script asking for paths never delays the robot's replanning). A path through poses
is planned leg by leg, each leg from the previous goal, and joined. Failures carry Nav2's codes (200s, and
300s through poses) with the planner's reason as ``error_msg``. One request at a time per action: a new
one preempts the running one, as Nav2's servers do.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from services.planner.costmap import LETHAL_OBSTACLE, NO_INFORMATION, CostGrid
from services.planner.global_planner import GlobalPlannerParams
from services.planner.goal_check import ACCEPTED_FRAMES, goal_pose
from services.planner.map_messages import path_message
from services.planner.planning_worker import PlanningWorker, PlanOutcome, PlanRequest
from services.planner.smoothing import smooth_path
from shared import topics
from shared.action import ActionServer, ServerGoalHandle
from shared.geometry import Pose2D, yaw_from_quaternion
from shared.interfaces.navigation import (
    COMPUTE_PATH_THROUGH_POSES,
    COMPUTE_PATH_TO_POSE,
    NO_VIAPOINTS_GIVEN,
    SMOOTH_PATH,
    ComputePathErrorCode,
    ComputePathThroughPosesGoal,
    ComputePathToPoseGoal,
    SmoothPathErrorCode,
    SmoothPathGoal,
    through_poses_code,
)
from shared.messages import Duration
from shared.node import Node

#: The planner_id a script may name: Nav2's default planner plugin's, or none.
PLANNER_IDS = ("", "GridBased")
#: The smoother_id a script may name: Nav2's default smoother plugin's, or none.
SMOOTHER_IDS = ("", "simple_smoother")


class _Request:
    """One path request under way: its legs, the poses planned so far, when it began."""

    def __init__(self, handle: ServerGoalHandle[Any, Any, Any], through: bool, legs: list[Pose2D]) -> None:
        self.handle = handle
        self.through = through
        self.goals = legs
        self.next_leg = 0
        self.poses: list[np.ndarray] = []
        self.started_wall_s = time.monotonic()


def outcome_code(outcome: PlanOutcome) -> ComputePathErrorCode:
    """Nav2's reason for a failed plan, from which end the planner could not use and why."""
    outside = "outside the map" in outcome.error
    if outcome.blocked_end == "start":
        return ComputePathErrorCode.START_OUTSIDE_MAP if outside else ComputePathErrorCode.START_OCCUPIED
    if outcome.blocked_end == "goal":
        return ComputePathErrorCode.GOAL_OUTSIDE_MAP if outside else ComputePathErrorCode.GOAL_OCCUPIED
    return (
        ComputePathErrorCode.NO_VALID_PATH
        if outcome.error.startswith("no path")
        else ComputePathErrorCode.UNKNOWN
    )


class PathServer:
    """Serves both path actions on ``node``; ``robot_pose()`` and ``grid()`` give the planner's current ones."""

    def __init__(
        self,
        node: Node,
        params: GlobalPlannerParams,
        *,
        robot_pose: Callable[[], Pose2D | None],
        grid: Callable[[], CostGrid | None],
        footprint_m: tuple[float, float],
    ) -> None:
        """``footprint_m``: the robot's length and width, for ``smooth_path``'s collision check."""
        self._node = node
        self._log = node.log
        self._robot_pose = robot_pose
        self._grid = grid
        self._worker = PlanningWorker(params, lambda outcome: node.post(self._on_outcome, outcome))
        self._generations = itertools.count(1)
        self._requests: dict[int, _Request] = {}
        self._servers: list[ActionServer[Any, Any, Any]] = [
            ActionServer(
                node,
                action,
                name,
                on_accepted=self._on_accepted,
                on_cancel=self._on_cancel,
                preempt_result=_preempted(action),
            )
            for action, name in (
                (COMPUTE_PATH_TO_POSE, topics.COMPUTE_PATH_TO_POSE),
                (COMPUTE_PATH_THROUGH_POSES, topics.COMPUTE_PATH_THROUGH_POSES),
            )
        ]
        self._servers.append(
            ActionServer(
                node,
                SMOOTH_PATH,
                topics.SMOOTH_PATH,
                on_accepted=self._on_smooth,
                on_cancel=lambda handle: None,  # answered within the call that accepts it
            )
        )
        self._smoothing = params.smoothing
        self._footprint = footprint_m

    def _on_smooth(self, handle: ServerGoalHandle[Any, Any, Any]) -> None:
        """``smooth_path``: the given path shortcut and smoothed within the costmap's costs, as a plan is.
        It takes milliseconds, so it is answered at once on the node's thread."""
        if not handle.active:
            return
        handle.execute()
        goal: SmoothPathGoal = handle.goal
        started = time.monotonic()

        def fail(code: SmoothPathErrorCode, reason: str) -> None:
            self._log.info("%s failed (%d): %s", topics.SMOOTH_PATH, code, reason)
            handle.abort(SMOOTH_PATH.result(error_code=int(code), error_msg=reason))

        grid = self._grid()
        frames = {p.header.frame_id.strip().lstrip("/") for p in goal.path.poses} | {
            goal.path.header.frame_id.strip().lstrip("/")
        }
        if goal.smoother_id not in SMOOTHER_IDS:
            return fail(
                SmoothPathErrorCode.INVALID_SMOOTHER,
                f"smoother_id {goal.smoother_id!r} is not one of zendock's ({', '.join(map(repr, SMOOTHER_IDS))})",
            )
        if len(goal.path.poses) < 2:
            return fail(
                SmoothPathErrorCode.INVALID_PATH, f"a path of {len(goal.path.poses)} poses: 2 at least"
            )
        if not frames <= set(ACCEPTED_FRAMES):
            return fail(
                SmoothPathErrorCode.INVALID_PATH, f"the path is not in the map frame: {sorted(frames)}"
            )
        if grid is None:
            return fail(SmoothPathErrorCode.UNKNOWN, "no map loaded: load one with map_server/load_map first")
        points = np.array([[p.pose.position.x, p.pose.position.y] for p in goal.path.poses], dtype=float)
        if not np.isfinite(points).all():
            return fail(SmoothPathErrorCode.INVALID_PATH, "the path has a pose that is not finite")
        last = goal.path.poses[-1].pose.orientation
        try:
            poses = smooth_path(
                grid, points, yaw_from_quaternion(last.x, last.y, last.z, last.w), self._smoothing
            )
        except ValueError as exc:
            return fail(SmoothPathErrorCode.FAILED_TO_SMOOTH_PATH, str(exc))
        elapsed = time.monotonic() - started
        allowed = goal.max_smoothing_duration.to_sec()
        if allowed > 0.0 and elapsed > allowed:
            return fail(SmoothPathErrorCode.TIMEOUT, f"smoothing took {elapsed:.3f} s, over {allowed:g} s")
        if goal.check_for_collisions:
            costs = grid.footprint_costs(poses, *self._footprint)
            hit = np.nonzero((costs >= LETHAL_OBSTACLE) & (costs != NO_INFORMATION))[0]
            if len(hit):
                x, y = poses[hit[0], :2]
                return fail(
                    SmoothPathErrorCode.SMOOTHED_PATH_IN_COLLISION,
                    f"the smoothed path puts the robot on an obstacle at ({x:.2f}, {y:.2f})",
                )
        path = path_message(poses, self._node.now(), topics.MAP_FRAME)
        handle.succeed(
            SMOOTH_PATH.result(path=path, smoothing_duration=Duration.from_sec(elapsed), was_completed=True)
        )

    def _on_accepted(self, handle: ServerGoalHandle[Any, Any, Any]) -> None:
        if not handle.active:
            return
        through = isinstance(handle.goal, ComputePathThroughPosesGoal)
        handle.execute()
        goal: ComputePathToPoseGoal | ComputePathThroughPosesGoal = handle.goal
        try:
            if goal.planner_id not in PLANNER_IDS:
                raise _Refusal(
                    ComputePathErrorCode.INVALID_PLANNER,
                    f"planner_id {goal.planner_id!r} is not one of zendock's ({', '.join(map(repr, PLANNER_IDS))})",
                )
            if isinstance(goal, ComputePathThroughPosesGoal):
                if not goal.goals:
                    raise _Refusal(None, "no goals to plan through")
                targets = [_pose(g) for g in goal.goals]
            else:
                targets = [_pose(goal.goal)]
            start = _pose(goal.start) if goal.use_start else self._robot_pose()
            if start is None:
                raise _Refusal(
                    ComputePathErrorCode.TF_ERROR, "no robot pose yet: give a start with use_start"
                )
            if self._grid() is None:
                raise _Refusal(
                    ComputePathErrorCode.UNKNOWN, "no map loaded: load one with map_server/load_map first"
                )
        except _Refusal as refusal:
            self._finish(handle, through, refusal.code, refusal.reason)
            return
        request = _Request(handle, through, [start, *targets])
        self._plan_next_leg(request)

    def _plan_next_leg(self, request: _Request) -> None:
        grid = self._grid()
        assert grid is not None
        generation = next(self._generations)
        self._requests = {g: r for g, r in self._requests.items() if r.handle.active}
        self._requests[generation] = request
        leg = request.next_leg
        self._worker.submit(PlanRequest(generation, grid, request.goals[leg], request.goals[leg + 1]))

    def _on_outcome(self, outcome: PlanOutcome) -> None:
        request = self._requests.pop(outcome.request.generation, None)
        if request is None or not request.handle.active:
            return  # canceled or preempted meanwhile
        if outcome.path is None:
            leg = f" (leg {request.next_leg + 1} of {len(request.goals) - 1})" if request.through else ""
            self._finish(request.handle, request.through, outcome_code(outcome), outcome.error + leg, request)
            return
        poses = outcome.path.poses if not request.poses else outcome.path.poses[1:]
        request.poses.append(poses)
        request.next_leg += 1
        if request.next_leg < len(request.goals) - 1:
            self._plan_next_leg(request)
            return
        self._finish(request.handle, request.through, ComputePathErrorCode.NONE, "", request)

    def _finish(
        self,
        handle: ServerGoalHandle[Any, Any, Any],
        through: bool,
        code: ComputePathErrorCode | None,
        reason: str,
        request: _Request | None = None,
    ) -> None:
        action = COMPUTE_PATH_THROUGH_POSES if through else COMPUTE_PATH_TO_POSE
        name = topics.COMPUTE_PATH_THROUGH_POSES if through else topics.COMPUTE_PATH_TO_POSE
        elapsed = time.monotonic() - request.started_wall_s if request is not None else 0.0
        if code is None:
            wire_code = NO_VIAPOINTS_GIVEN
        else:
            wire_code = through_poses_code(code) if through else int(code)
        if wire_code:
            self._log.info("%s failed (%d): %s", name, wire_code, reason)
            handle.abort(
                action.result(
                    planning_time=Duration.from_sec(elapsed), error_code=wire_code, error_msg=reason
                )
            )
            return
        assert request is not None
        poses = np.concatenate(request.poses)
        path = path_message(poses, self._node.now(), topics.MAP_FRAME)
        self._log.info("%s: %d poses in %.0f ms", name, len(poses), 1e3 * elapsed)
        handle.succeed(action.result(path=path, planning_time=Duration.from_sec(elapsed)))

    def _on_cancel(self, handle: ServerGoalHandle[Any, Any, Any]) -> None:
        if handle.active:
            handle.canceled(handle.action.result(error_msg="canceled on request"))

    def close(self) -> None:
        self._worker.close()
        for server in self._servers:
            server.close()


class _Refusal(Exception):
    def __init__(self, code: ComputePathErrorCode | None, reason: str) -> None:
        super().__init__(reason)
        self.code = code
        self.reason = reason


def _pose(stamped: Any) -> Pose2D:
    """A goal or start as a map pose: another frame is Nav2's TF_ERROR (zendock plans in ``map`` only)."""
    if stamped.header.frame_id.strip().lstrip("/") not in ACCEPTED_FRAMES:
        raise _Refusal(
            ComputePathErrorCode.TF_ERROR, f"frame_id {stamped.header.frame_id!r} is not the map frame"
        )
    try:
        return goal_pose(stamped)
    except ValueError as exc:
        raise _Refusal(ComputePathErrorCode.UNKNOWN, str(exc)) from None


def _preempted(action: Any) -> Callable[[], Any]:
    return lambda: action.result(error_msg="preempted by a newer request")
