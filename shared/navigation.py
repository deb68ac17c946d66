"""A navigation client shaped like Nav2's simple commander, for scripts, tools, tests and services.

    nav = NavigationClient(node)            # node spun by the caller, or spin_in_background(node)
    nav.wait_until_active()
    nav.go_to_pose(Pose2D(0.0, 2.0, 0.0))
    while not nav.is_task_complete():
        print(nav.get_feedback().distance_remaining)
    if nav.get_result() is TaskResult.SUCCEEDED: ...

``go_to_pose`` returns as soon as the goal is sent; acceptance or rejection shows up in
``is_task_complete``/``get_result``, so a service may call every method from its own callbacks. Only
:meth:`wait_until_active`, :meth:`clear_all_costmaps` and :meth:`change_map` block, and they refuse to
run on the node's executor thread.
"""

from __future__ import annotations

import enum
from collections.abc import Callable

from shared.action import ActionClient, ClientGoal
from shared.geometry import Pose2D
from shared.interface_types import GoalStatusCode
from shared.interfaces.navigation import (
    CLEAR_COSTMAPS_SERVICE,
    CLEAR_ENTIRE_COSTMAP,
    LOAD_MAP,
    LOAD_MAP_SERVICE,
    NAVIGATE_TO_POSE,
    ClearEntireCostmapRequest,
    LoadMapRequest,
    LoadMapResponse,
    NavigateToPoseFeedback,
    NavigateToPoseGoal,
    NavigateToPoseResult,
)
from shared.messages import Header, Pose, PoseStamped
from shared.node import Node
from shared.topics import MAP_FRAME
from shared.topics import NAVIGATE_TO_POSE as NAVIGATE_ACTION


class TaskResult(enum.Enum):
    UNKNOWN = 0
    SUCCEEDED = 1
    CANCELED = 2
    FAILED = 3


class NavigationClient:
    """Drives the ``navigate_to_pose`` action of the planner in the node's namespace."""

    def __init__(self, node: Node, action_name: str = NAVIGATE_ACTION) -> None:
        self.node = node
        self._client = ActionClient(node, NAVIGATE_TO_POSE, action_name)
        self._goal: ClientGoal[NavigateToPoseResult, NavigateToPoseFeedback] | None = None

    def wait_until_active(self, timeout_s: float = 30.0) -> bool:
        """Block until the navigation server is up; ``False`` after the timeout."""
        return self._client.server_ready(timeout_s=timeout_s)

    def go_to_pose(self, pose: Pose2D | PoseStamped, on_done: Callable[[], None] | None = None) -> None:
        """Send a goal (map frame); the previous goal of this client is forgotten (the server preempts it).
        ``on_done`` runs on the executor once this goal has ended (succeeded, canceled, failed or refused),
        also when a newer goal has replaced it meanwhile."""
        if isinstance(pose, Pose2D):
            pose = PoseStamped(Header.at(self.node.now(), MAP_FRAME), Pose.from_pose2d(pose))
        if self._goal is not None:
            self._client.forget(self._goal)
        done = None if on_done is None else (lambda _goal: on_done())
        self._goal = self._client.send_goal(NavigateToPoseGoal(pose=pose), on_done=done)

    def is_task_complete(self) -> bool:
        """True once the goal ended, was rejected, or its server went away; also True with no goal."""
        goal = self._goal
        if goal is None:
            return True
        with self._client.lock:
            return goal.done

    def get_feedback(self) -> NavigateToPoseFeedback | None:
        goal = self._goal
        if goal is None:
            return None
        with self._client.lock:
            return goal.feedback

    def get_result(self) -> TaskResult:
        goal = self._goal
        if goal is None:
            return TaskResult.UNKNOWN
        with self._client.lock:
            if goal.accepted is False or goal.error:
                return TaskResult.FAILED
            return {
                GoalStatusCode.SUCCEEDED: TaskResult.SUCCEEDED,
                GoalStatusCode.CANCELED: TaskResult.CANCELED,
                GoalStatusCode.ABORTED: TaskResult.FAILED,
            }.get(goal.status, TaskResult.UNKNOWN)

    def get_result_detail(self) -> NavigateToPoseResult | None:
        """The server's result message (error code and message), once the goal has ended."""
        goal = self._goal
        return goal.result if goal is not None else None

    def failure_reason(self) -> str:
        goal = self._goal
        if goal is None:
            return ""
        if goal.rejection or goal.error:
            return goal.rejection or goal.error
        return goal.result.error_msg if goal.result is not None else ""

    def cancel_task(self) -> None:
        """Ask the server to cancel the current goal (returns at once; the robot stops within a tick)."""
        if self._goal is not None and not self.is_task_complete():
            self._client.cancel_goal(self._goal)

    def clear_all_costmaps(self, timeout_s: float = 5.0) -> None:
        self.node.call(CLEAR_ENTIRE_COSTMAP, CLEAR_COSTMAPS_SERVICE, ClearEntireCostmapRequest(), timeout_s)

    def change_map(self, map_yaml_path: str, timeout_s: float = 10.0) -> LoadMapResponse:
        return self.node.call(LOAD_MAP, LOAD_MAP_SERVICE, LoadMapRequest(map_url=map_yaml_path), timeout_s)
