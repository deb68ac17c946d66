"""ROS-like actions over Zenoh, with the key layout zenoh-bridge-ros2dds uses::

    <ns>/<action>/_action/send_goal     queryable   {goal_id, goal}      -> {accepted, stamp}
    <ns>/<action>/_action/cancel_goal   queryable   {goal_info}          -> {return_code, goals_canceling}
    <ns>/<action>/_action/get_result    queryable   {goal_id}            -> {status, result}  (answered when done)
    <ns>/<action>/_action/feedback      topic       {goal_id, feedback}
    <ns>/<action>/_action/status        topic       {status_list: [{goal_info, status}]}

Message layouts mirror ``action_msgs`` and the generated ``<Action>_SendGoal`` etc. types. A server
here runs one goal at a time: accepting a new goal preempts the active one (it ends CANCELED), as a
navigation server does. Everything runs on the node's executor: the server never blocks, and the
:class:`ActionClient` is asynchronous so services can use it from their callbacks.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Generic

import zenoh

from shared.interface_types import (
    CANCEL_GOAL,
    UUID,
    ActionType,
    CancelGoalRequest,
    CancelGoalResponse,
    F,
    G,
    GoalInfo,
    GoalStatus,
    GoalStatusArray,
    GoalStatusCode,
    R,
)
from shared.messages import Time
from shared.node import BLOCKING, RELIABLE, Node, ServiceError, encoding_for
from shared.schema import MessageError

#: How often :meth:`ActionClient.server_ready` asks again for a server that has not answered yet.
SERVER_POLL_S = 0.05
#: Finished goals an action server remembers (oldest forgotten first): a client may ask for a result, or
#: cancel a goal and be told it has ended, for this many goals after it ended.
KEPT_RESULTS = 64

log = logging.getLogger(__name__)


def action_key(action_name: str, part: str) -> str:
    """Relative key of one part of an action, e.g. ``navigate_to_pose/_action/send_goal``."""
    return f"{action_name.strip('/')}/_action/{part}"


# --- server ---------------------------------------------------------------------------------------


class ServerGoalHandle(Generic[G, R, F]):
    """One accepted goal on the server side. Finish it with exactly one of succeed / abort / canceled."""

    def __init__(self, server: ActionServer[G, R, F], goal_id: UUID, goal: G, stamp: Time) -> None:
        self._server = server
        self.goal_id = goal_id
        self.goal = goal
        self.info = GoalInfo(goal_id, stamp)
        self.status = GoalStatusCode.ACCEPTED
        self.cancel_requested = False
        self.result: R | None = None

    @property
    def id_hex(self) -> str:
        return self.goal_id.hex()

    @property
    def action(self) -> ActionType[G, R, F]:
        """The action this goal belongs to (for a server of several actions to build its result)."""
        return self._server.action

    @property
    def active(self) -> bool:
        return not self.status.terminal

    def execute(self) -> None:
        if self.status == GoalStatusCode.ACCEPTED:
            self._server._set_status(self, GoalStatusCode.EXECUTING)

    def publish_feedback(self, feedback: F) -> None:
        if self.active:
            self._server._publish_feedback(self, feedback)

    def succeed(self, result: R) -> None:
        self._server._finish(self, GoalStatusCode.SUCCEEDED, result)

    def abort(self, result: R) -> None:
        self._server._finish(self, GoalStatusCode.ABORTED, result)

    def canceled(self, result: R) -> None:
        self._server._finish(self, GoalStatusCode.CANCELED, result)


class ActionServer(Generic[G, R, F]):
    """Serves one action on a node.

    ``on_goal(goal) -> None`` validates a goal (raise ``ValueError(reason)`` to reject it: the client sees
    the reason); without one every goal is accepted. ``on_accepted(handle)`` starts work, normally by remembering the handle for a timer to
    step. ``on_cancel(handle)`` is told of a cancel request; it ends the goal itself (``handle.canceled``)
    once the robot is stopped. ``on_preempt(old)`` is told when a new goal replaces the active one;
    by default the old goal ends CANCELED with ``preempt_result()``.
    """

    def __init__(
        self,
        node: Node,
        action: ActionType[G, R, F],
        name: str,
        *,
        on_goal: Callable[[G], None] | None = None,
        on_accepted: Callable[[ServerGoalHandle[G, R, F]], None],
        on_cancel: Callable[[ServerGoalHandle[G, R, F]], None],
        preempt_result: Callable[[], R] | None = None,
    ) -> None:
        self.node = node
        self.action = action
        self.name = name
        self._on_goal = on_goal
        self._on_accepted = on_accepted
        self._on_cancel = on_cancel
        self._preempt_result = preempt_result or action.result
        self.active_goal: ServerGoalHandle[G, R, F] | None = None
        self._finished: dict[str, ServerGoalHandle[G, R, F]] = {}
        self._waiting: dict[str, list[zenoh.Query]] = {}
        self._feedback = node.create_publisher(
            action.feedback_message, action_key(name, "feedback"), RELIABLE
        )
        self._status = node.create_publisher(GoalStatusArray, action_key(name, "status"), BLOCKING)
        node.create_service(action.send_goal, action_key(name, "send_goal"), self._handle_send_goal)
        node.create_service(CANCEL_GOAL, action_key(name, "cancel_goal"), self._handle_cancel)
        self._result_key = node.key(action_key(name, "get_result"))
        self._result_queryable = node.session.declare_queryable(self._result_key, self._on_result_query)
        node.declare_endpoint("act", action.type_name, node.key(name))
        node.action_servers[name] = self

    # request handlers (executor thread)

    def _handle_send_goal(self, request: Any) -> Any:
        gate = self.node.work_gate
        refusal = gate(self.name) if gate is not None else None
        if refusal is not None:
            raise ValueError(refusal)
        if self._on_goal is not None:
            self._on_goal(request.goal)  # ValueError -> the client gets the reason
        handle: ServerGoalHandle[G, R, F] = ServerGoalHandle(
            self, request.goal_id, request.goal, self.node.now_msg()
        )
        previous = self.active_goal
        if previous is not None and previous.active:
            previous.cancel_requested = True
            self._finish(previous, GoalStatusCode.CANCELED, self._preempt_result())
        self.active_goal = handle
        self._publish_status()
        self.node.post(self._on_accepted, handle)
        return self.action.send_goal_response(accepted=True, stamp=handle.info.stamp)

    def cancel_active(self) -> bool:
        """Ask the running goal to stop, as a client's cancel would (its server stops the robot, then ends
        it CANCELED); False when none runs."""
        goal = self.active_goal
        if goal is None or not goal.active or goal.cancel_requested:
            return False
        goal.cancel_requested = True
        self._set_status(goal, GoalStatusCode.CANCELING)
        self.node.post(self._on_cancel, goal)
        return True

    def _handle_cancel(self, request: CancelGoalRequest) -> CancelGoalResponse:
        goal = self.active_goal
        wanted = request.goal_info.goal_id
        if goal is None or not goal.active:
            code = (
                CancelGoalResponse.ERROR_GOAL_TERMINATED if goal else CancelGoalResponse.ERROR_UNKNOWN_GOAL_ID
            )
            return CancelGoalResponse(return_code=code)
        if not wanted.is_zero() and wanted.hex() != goal.id_hex:
            known = wanted.hex() in self._finished
            code = (
                CancelGoalResponse.ERROR_GOAL_TERMINATED
                if known
                else CancelGoalResponse.ERROR_UNKNOWN_GOAL_ID
            )
            return CancelGoalResponse(return_code=code)
        goal.cancel_requested = True
        self._set_status(goal, GoalStatusCode.CANCELING)
        self.node.post(self._on_cancel, goal)
        return CancelGoalResponse(return_code=CancelGoalResponse.ERROR_NONE, goals_canceling=[goal.info])

    def _on_result_query(self, query: zenoh.Query) -> None:
        payload = query.payload
        try:
            request = self.action.get_result_request.decode(
                payload.to_bytes() if payload is not None else b""
            )
        except MessageError as exc:
            self.node.reject(self._result_key, exc.at(key=self._result_key))
            query.reply_err(str(exc).encode(), encoding=zenoh.Encoding("text/plain"))
            query.drop()
            return
        self.node.post(self._answer_result, query, request.goal_id.hex())

    def _answer_result(self, query: zenoh.Query, goal_hex: str) -> None:
        done = self._finished.get(goal_hex)
        if done is not None:
            self._reply_result(query, done)
        elif self.active_goal is not None and self.active_goal.id_hex == goal_hex:
            self._waiting.setdefault(goal_hex, []).append(query)  # answered when the goal ends
        else:
            query.reply_err(f"unknown goal {goal_hex}".encode(), encoding=zenoh.Encoding("text/plain"))
            query.drop()

    def _reply_result(self, query: zenoh.Query, handle: ServerGoalHandle[G, R, F]) -> None:
        response = self.action.get_result_response(status=int(handle.status), result=handle.result)
        try:
            query.reply(
                self._result_key,
                response.encode(),
                encoding=encoding_for(self.action.get_result_response.TYPE_NAME),
            )
        finally:
            query.drop()

    # goal handle callbacks

    def _set_status(self, handle: ServerGoalHandle[G, R, F], status: GoalStatusCode) -> None:
        handle.status = status
        self._publish_status()

    def _publish_feedback(self, handle: ServerGoalHandle[G, R, F], feedback: F) -> None:
        self._feedback.publish(self.action.feedback_message(goal_id=handle.goal_id, feedback=feedback))

    def _finish(self, handle: ServerGoalHandle[G, R, F], status: GoalStatusCode, result: R) -> None:
        if handle.status.terminal:
            return
        handle.status = status
        handle.result = result
        self._finished[handle.id_hex] = handle
        if len(self._finished) > KEPT_RESULTS:
            self._finished.pop(next(iter(self._finished)))
        self._publish_status()
        for query in self._waiting.pop(handle.id_hex, []):
            self._reply_result(query, handle)

    def _publish_status(self) -> None:
        handles = list(self._finished.values())[-8:]
        if self.active_goal is not None and self.active_goal.active:
            handles.append(self.active_goal)
        self._status.publish(GoalStatusArray([GoalStatus(h.info, int(h.status)) for h in handles]))

    def close(self) -> None:
        for queries in self._waiting.values():
            for query in queries:
                query.reply_err(b"action server shutting down", encoding=zenoh.Encoding("text/plain"))
                query.drop()
        self._waiting.clear()
        self._result_queryable.undeclare()


# --- client ---------------------------------------------------------------------------------------


@dataclass
class ClientGoal(Generic[R, F]):
    """What a client knows of one goal it sent. Read it from the node's executor thread (or under ``lock``)."""

    goal_id: UUID
    accepted: bool | None = None
    rejection: str = ""
    status: GoalStatusCode = GoalStatusCode.UNKNOWN
    result: R | None = None
    feedback: F | None = None
    error: str = ""
    sent_at: float = field(default_factory=time.monotonic)

    @property
    def done(self) -> bool:
        return self.accepted is False or self.status.terminal or bool(self.error)


class ActionClient(Generic[G, R, F]):
    """Sends goals to an action server; every reply lands on the node's executor (never blocks it).

    Scripts that do not spin the node themselves can use :meth:`spin_in_background`.
    """

    def __init__(self, node: Node, action: ActionType[G, R, F], name: str) -> None:
        self.node = node
        self.action = action
        self.name = name
        self.lock = threading.Lock()
        self._goals: dict[str, ClientGoal[R, F]] = {}
        self._feedback_cbs: dict[str, Callable[[F], None]] = {}
        node.create_subscription(
            action.feedback_message, action_key(name, "feedback"), self._on_feedback, RELIABLE
        )
        node.create_subscription(GoalStatusArray, action_key(name, "status"), self._on_status, RELIABLE)

    def server_ready(self, timeout_s: float = 1.0) -> bool:
        """Whether an action server answers (its send_goal queryable is declared) within ``timeout_s``.

        A liveliness query sees only the tokens the router knows when the query reaches it: a server that
        comes up, or whose token is still on its way, a moment later is missed. So the query is repeated
        until a server answers or the time is up, as ROS 2's ``wait_for_server`` waits.
        """
        token_pattern = f"@zendock/act/**/{self.node.key(self.name)}"
        deadline = time.monotonic() + timeout_s
        while True:
            remaining_s = deadline - time.monotonic()
            replies = self.node.session.liveliness().get(
                token_pattern, timeout=max(0.05, min(remaining_s, 1.0))
            )
            if any(r.ok is not None for r in replies):
                return True
            if time.monotonic() + SERVER_POLL_S >= deadline:
                return False
            time.sleep(SERVER_POLL_S)

    def send_goal(
        self,
        goal: G,
        on_feedback: Callable[[F], None] | None = None,
        on_done: Callable[[ClientGoal[R, F]], None] | None = None,
        timeout_s: float = 5.0,
    ) -> ClientGoal[R, F]:
        """Send a goal; returns at once. ``on_done`` runs on the executor when the goal ends or fails."""
        handle: ClientGoal[R, F] = ClientGoal(UUID.random())
        key = handle.goal_id.hex()
        with self.lock:
            self._goals[key] = handle
            if on_feedback is not None:
                self._feedback_cbs[key] = on_feedback
        request = self.action.send_goal_request(goal_id=handle.goal_id, goal=goal)

        def accepted(response: Any, error: ServiceError | None) -> None:
            with self.lock:
                if error is not None or response is None:
                    handle.accepted = False
                    handle.rejection = str(error) if error else "no response"
                elif not response.accepted:
                    handle.accepted = False
                    handle.rejection = "goal rejected by the server"
                else:
                    handle.accepted = True
                    if handle.status == GoalStatusCode.UNKNOWN:
                        handle.status = GoalStatusCode.ACCEPTED
            if handle.accepted:
                self._request_result(handle, on_done)
            elif on_done is not None:
                on_done(handle)

        self.node.call_async(
            self.action.send_goal, action_key(self.name, "send_goal"), request, accepted, timeout_s
        )
        return handle

    def _request_result(
        self, handle: ClientGoal[R, F], on_done: Callable[[ClientGoal[R, F]], None] | None
    ) -> None:
        request = self.action.get_result_request(goal_id=handle.goal_id)

        def got(response: Any, error: ServiceError | None) -> None:
            with self.lock:
                if error is not None or response is None:
                    handle.error = str(error) if error else "no result"
                else:
                    handle.status = GoalStatusCode(response.status)
                    handle.result = response.result
                self._feedback_cbs.pop(handle.goal_id.hex(), None)
            if on_done is not None:
                on_done(handle)

        self.node.call_async(
            self.action.get_result, action_key(self.name, "get_result"), request, got, timeout_s=3600.0
        )

    def cancel_goal(
        self,
        handle: ClientGoal[R, F] | None = None,
        timeout_s: float = 5.0,
        on_done: Callable[[CancelGoalResponse | None, ServiceError | None], None] | None = None,
    ) -> None:
        """Ask the server to cancel ``handle`` (or every goal when ``None``); returns at once."""
        goal_id = handle.goal_id if handle is not None else UUID()
        request = CancelGoalRequest(GoalInfo(goal_id, Time()))
        self.node.call_async(
            CANCEL_GOAL,
            action_key(self.name, "cancel_goal"),
            request,
            on_done or (lambda _r, _e: None),
            timeout_s,
        )

    def _on_feedback(self, msg: Any) -> None:
        key = msg.goal_id.hex()
        with self.lock:
            handle = self._goals.get(key)
            if handle is None:
                return
            handle.feedback = msg.feedback
            callback = self._feedback_cbs.get(key)
        if callback is not None:
            callback(msg.feedback)

    def _on_status(self, msg: GoalStatusArray) -> None:
        with self.lock:
            for status in msg.status_list:
                handle = self._goals.get(status.goal_info.goal_id.hex())
                if handle is not None and not handle.status.terminal:
                    # the terminal status comes with the result; status only tracks progress
                    code = GoalStatusCode(status.status)
                    if not code.terminal:
                        handle.status = code

    def forget(self, handle: ClientGoal[R, F]) -> None:
        with self.lock:
            self._goals.pop(handle.goal_id.hex(), None)
            self._feedback_cbs.pop(handle.goal_id.hex(), None)


def spin_in_background(node: Node) -> threading.Thread:
    """Run a node's executor on a daemon thread (for scripts and tests); stop it with ``node.shutdown()``."""
    thread = threading.Thread(target=node.spin, name=f"{node.name}-executor", daemon=True)
    thread.start()
    return thread
