"""``follow_waypoints`` and ``navigate_through_poses``: the planner's own ``navigate_to_pose``, one pose
after another, as Nav2's waypoint_follower drives its navigator.

Each pose is a ``navigate_to_pose`` goal sent on the bus (:class:`shared.navigation.NavigationClient`),
so a leg is exactly a navigation goal: the same checks, recoveries, glass slowdowns and refusals. The
robot stops at each pose (Nav2's navigate_through_poses passes through them; zendock's arrives at each in
turn). A waypoint that fails is recorded in ``missed_waypoints`` with its navigation error code, and the
follower goes on to the next unless ``waypoint_stop_on_failure`` (Nav2's ``stop_on_failure``) is set;
through poses, a failed leg ends the goal with that leg's code and reason. A newer goal on either action
ends the one running. So does a ``navigate_to_pose`` goal from anyone else (zendock's docking, say): the
sequence ends there rather than take the robot back with its next leg.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

from shared import topics
from shared.action import ActionServer, ServerGoalHandle
from shared.executor import Timer
from shared.interfaces.navigation import (
    FOLLOW_GPS_WAYPOINTS,
    FOLLOW_WAYPOINTS,
    NAVIGATE_THROUGH_POSES,
    FollowWaypointsErrorCode,
    FollowWaypointsFeedback,
    FollowWaypointsGoal,
    MissedWaypoint,
    NavigateErrorCode,
    NavigateThroughPosesFeedback,
)
from shared.messages import Duration, PoseStamped
from shared.navigation import NavigationClient, TaskResult
from shared.node import Node


class _Task:
    """One sequence under way: its goal, which pose is next, what was missed."""

    def __init__(
        self, handle: ServerGoalHandle[Any, Any, Any], poses: list[PoseStamped], first: int, rounds: int
    ):
        self.handle = handle
        self.poses = poses
        self.index = first
        self.rounds_left = rounds
        self.missed: list[MissedWaypoint] = []
        self.recoveries = 0
        self.started_wall_s = time.monotonic()
        self.canceling = False

    @property
    def waypoints(self) -> bool:
        return isinstance(self.handle.goal, FollowWaypointsGoal)


class PoseSequences:
    """Serves both actions on ``node``; ``stop_on_failure()`` reads the planner's parameter when needed."""

    def __init__(self, node: Node, stop_on_failure: Callable[[], bool]) -> None:
        self._node = node
        self._log = node.log
        self._stop_on_failure = stop_on_failure
        # Both made with the first goal: until a script asks for a sequence, the planner neither reads its
        # own navigation feedback nor wakes for this feedback (flat out, every wake-up costs sim time).
        self._client: NavigationClient | None = None
        self._timer: Timer | None = None
        self._task: _Task | None = None
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
                (FOLLOW_WAYPOINTS, topics.FOLLOW_WAYPOINTS),
                (NAVIGATE_THROUGH_POSES, topics.NAVIGATE_THROUGH_POSES),
            )
        ]
        self._servers.append(
            ActionServer(
                node,
                FOLLOW_GPS_WAYPOINTS,
                topics.FOLLOW_GPS_WAYPOINTS,
                on_accepted=_refuse_gps,
                on_cancel=lambda handle: None,  # ended within the call that accepts it
            )
        )

    @property
    def _navigation(self) -> NavigationClient:
        if self._client is None:
            self._client = NavigationClient(self._node)
        return self._client

    def _on_accepted(self, handle: ServerGoalHandle[Any, Any, Any]) -> None:
        if not handle.active:
            return
        handle.execute()
        previous = self._task
        if previous is not None and previous.handle.active:
            previous.handle.canceled(self._result(previous, 0, "preempted by a newer goal"))
        goal = handle.goal
        if not goal.poses:
            self._task = None
            code = FollowWaypointsErrorCode.UNKNOWN if isinstance(goal, FollowWaypointsGoal) else 0
            handle.abort(handle.action.result(error_code=int(code), error_msg="no poses to go to"))
            return
        if isinstance(goal, FollowWaypointsGoal):
            if goal.goal_index >= len(goal.poses):
                self._task = None
                handle.abort(
                    FOLLOW_WAYPOINTS.result(
                        error_code=int(FollowWaypointsErrorCode.UNKNOWN),
                        error_msg=f"goal_index {goal.goal_index} is past the last of {len(goal.poses)} waypoints",
                    )
                )
                return
            task = _Task(handle, list(goal.poses), goal.goal_index, goal.number_of_loops)
        else:
            task = _Task(handle, list(goal.poses), 0, 0)
        self._task = task
        self._log.info(
            "%s: %d poses",
            "follow_waypoints" if task.waypoints else "navigate_through_poses",
            len(task.poses),
        )
        self._next_leg(task)

    def _next_leg(self, task: _Task) -> None:
        if self._timer is None:
            self._timer = self._node.create_timer(0.2, self._publish_feedback, wall=True)
        index = task.index
        self._navigation.go_to_pose(task.poses[index], on_done=lambda: self._leg_done(task, index))
        self._publish_feedback()

    def _leg_done(self, task: _Task, index: int) -> None:
        if task is not self._task or not task.handle.active or index != task.index:
            return  # an earlier goal's leg, ended by the newer one
        outcome = self._navigation.get_result()
        detail = self._navigation.get_result_detail()
        feedback = self._navigation.get_feedback()
        if feedback is not None:
            task.recoveries += feedback.number_of_recoveries
        if task.canceling:
            self._task = None
            task.handle.canceled(self._result(task, 0, "canceled on request"))
            return
        if outcome is not TaskResult.SUCCEEDED:
            code = (
                detail.error_code
                if detail is not None and detail.error_code
                else NavigateErrorCode.INVALID_GOAL
            )
            reason = self._navigation.failure_reason() or outcome.name.lower()
            # Canceled without our asking: another navigate_to_pose goal (zendock's docking, say) took the
            # robot. Going on to the next waypoint would take it back, so the sequence ends here.
            taken = outcome is TaskResult.CANCELED
            if taken:
                reason = f"navigate_to_pose was taken by another goal ({reason or 'preempted'})"
            if taken or not task.waypoints or self._stop_on_failure():
                self._task = None
                self._log.info("pose %d of %d failed (%d): %s", index + 1, len(task.poses), code, reason)
                final = FollowWaypointsErrorCode.TASK_EXECUTOR_FAILED if task.waypoints else code
                if task.waypoints:
                    task.missed.append(MissedWaypoint(index, task.poses[index], int(code)))
                task.handle.abort(self._result(task, int(final), f"pose {index + 1}: {reason}"))
                return
            self._log.info("waypoint %d missed (%d): %s", index + 1, code, reason)
            task.missed.append(MissedWaypoint(index, task.poses[index], int(code)))
        task.index += 1
        if task.index >= len(task.poses) and task.rounds_left > 0:
            task.rounds_left -= 1
            task.index = 0
        if task.index < len(task.poses):
            self._next_leg(task)
            return
        self._task = None
        self._log.info("%d poses done, %d missed", len(task.poses), len(task.missed))
        task.handle.succeed(self._result(task, 0, ""))

    def _result(self, task: _Task, code: int, message: str) -> Any:
        if task.waypoints:
            return FOLLOW_WAYPOINTS.result(
                missed_waypoints=list(task.missed), error_code=code, error_msg=message
            )
        return NAVIGATE_THROUGH_POSES.result(error_code=code, error_msg=message)

    def _on_cancel(self, handle: ServerGoalHandle[Any, Any, Any]) -> None:
        task = self._task
        if task is not None and task.handle is handle:
            task.canceling = True
            if self._navigation.is_task_complete():
                self._task = None
                handle.canceled(self._result(task, 0, "canceled on request"))
            else:
                self._navigation.cancel_task()  # the leg's end finishes the cancel
        elif handle.active:
            handle.canceled(handle.action.result(error_msg="canceled on request"))

    def _publish_feedback(self) -> None:
        task = self._task
        if task is None or not task.handle.active:
            if self._timer is not None:  # nothing to report until the next goal
                self._timer.cancel()
                self._timer = None
            return
        if task.waypoints:
            task.handle.publish_feedback(FollowWaypointsFeedback(current_waypoint=task.index))
            return
        leg = self._navigation.get_feedback()
        later = _straight_line_m(task.poses[task.index :])
        task.handle.publish_feedback(
            NavigateThroughPosesFeedback(
                current_pose=leg.current_pose if leg is not None else PoseStamped(),
                navigation_time=Duration.from_sec(time.monotonic() - task.started_wall_s),
                estimated_time_remaining=leg.estimated_time_remaining if leg is not None else Duration(),
                number_of_recoveries=task.recoveries + (leg.number_of_recoveries if leg is not None else 0),
                distance_remaining=(leg.distance_remaining if leg is not None else 0.0) + later,
                number_of_poses_remaining=len(task.poses) - task.index,
            )
        )

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
        if self._task is not None and self._task.handle.active:
            self._task.handle.abort(self._result(self._task, 0, "the planner is shutting down"))
        self._task = None
        for server in self._servers:
            server.close()


def _preempted(action: Any) -> Callable[[], Any]:
    return lambda: action.result(error_msg="preempted by a newer goal")


def _straight_line_m(poses: list[PoseStamped]) -> float:
    """The length of the straight lines joining ``poses``: the rest of the way after the current leg."""
    points = [(p.pose.position.x, p.pose.position.y) for p in poses]
    return sum(math.dist(a, b) for a, b in zip(points, points[1:], strict=False))


#: Why ``follow_gps_waypoints`` is refused: no world of zendock's is placed on the globe.
GPS_REFUSAL = (
    "follow_gps_waypoints is not served: zendock's worlds have no GPS and no map-to-globe datum; "
    "give the waypoints as map poses to follow_waypoints"
)


def _refuse_gps(handle: ServerGoalHandle[Any, Any, Any]) -> None:
    """Accept and end at once with the reason (a rejection would reach a ROS 2 client without one)."""
    if handle.active:
        handle.execute()
        handle.abort(
            FOLLOW_GPS_WAYPOINTS.result(
                error_code=int(FollowWaypointsErrorCode.UNKNOWN), error_msg=GPS_REFUSAL
            )
        )
