"""The ``zendock_robot`` fixture's handle: drive a running stack's robot from a test, through ``shared`` only.

A test talks to the robot the way zendock's own tools do (``zendock dock``, ``zendock nav``,
``zendock battery``): a :class:`shared.node.Node` on its own Zenoh session, connected to the stack's
endpoint, with the docking service's actions, the planner's navigation client and the battery's
``set_state`` request. Everything that waits has a timeout and fails saying what it did see, so a red
test explains itself; nothing sleeps blindly.

The handle keeps a reference to every subscriber it declares (Zenoh undeclares a subscriber whose object
is collected) and closes its node and session in :meth:`Robot.close`, which the fixture calls.
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import zenoh

from shared import topics
from shared.action import ActionClient, ClientGoal, spin_in_background
from shared.encoding import schema_of
from shared.geometry import Pose2D
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest, SetBatteryStateResponse
from shared.interfaces.docking import (
    DOCK_ROBOT,
    UNDOCK_ROBOT,
    DockRobotGoal,
    DockRobotResult,
    UndockRobotGoal,
    UndockRobotResult,
)
from shared.interfaces.navigation import NavigateToPoseResult
from shared.interfaces.simulator import SIM_STATE, SimStateRequest, SimStateResponse
from shared.messages import BatteryState, Float64MultiArray
from shared.navigation import NavigationClient, TaskResult
from shared.node import Node, Publisher, ServiceUnavailable
from shared.schema import Message, MessageError, message_type
from shared.session import SessionSpec, open_session

#: How long the handle waits for an action server (the docking service, the planner) to answer.
SERVER_TIMEOUT_S = 30.0
#: How long a blocking request (battery, simulator state) keeps being retried while nobody answers.
REQUEST_TIMEOUT_S = 20.0
#: How many messages per key a recording keeps for :meth:`Robot.wait_for`'s failure message.
KEEP = 200


class WaitTimeout(AssertionError):
    """A wait of the robot handle ran out; the message says what did arrive (an assertion: the test fails)."""


def decode_sample(sample: zenoh.Sample, msg_type: type[Message] | None = None) -> Message:
    """A zendock sample as a message: of ``msg_type``, or of the type its encoding names."""
    if msg_type is None:
        _mime, type_name = schema_of(sample.encoding)
        try:
            msg_type = message_type(type_name)
        except KeyError:
            raise MessageError(f"no message type {type_name!r} is known (pass msg_type=)") from None
    return msg_type.decode(sample.payload.to_bytes())


class KeyRecording:
    """What arrives on one key from the moment it is watched: decoded messages and undecodable payloads."""

    def __init__(self, session: zenoh.Session, key: str, msg_type: type[Message] | None) -> None:
        self.key = key
        self.msg_type = msg_type
        self.count = 0
        self.messages: list[Message] = []
        self.errors: list[str] = []
        self._changed = threading.Condition()
        self._subscriber = session.declare_subscriber(key, self._on_sample)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        try:
            msg = decode_sample(sample, self.msg_type)
        except MessageError as exc:
            with self._changed:
                self.errors = [*self.errors[-KEEP + 1 :], str(exc)]
                self._changed.notify_all()
            return
        with self._changed:
            self.count += 1
            self.messages.append(msg)
            del self.messages[:-KEEP]
            self._changed.notify_all()

    def wait_for(self, predicate: Callable[[Any], bool], timeout_s: float, what: str) -> Any:
        """The latest message already here, or the first to come, that satisfies ``predicate``."""
        deadline = time.monotonic() + timeout_s
        with self._changed:
            checked = max(self.count - 1, 0)
            while True:
                first_kept = self.count - len(self.messages)
                for index in range(max(checked, first_kept), self.count):
                    msg = self.messages[index - first_kept]
                    if predicate(msg):
                        return msg
                checked = self.count
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise WaitTimeout(
                        self.describe(f"no message on {self.key} {what} within {timeout_s:g} s")
                    )
                self._changed.wait(min(remaining, 0.5))

    def describe(self, headline: str) -> str:
        last = [repr(m)[:240] for m in self.messages[-3:]]
        return (
            f"{headline}; {self.count} message(s) arrived, {len(self.errors)} undecodable"
            + (f"; the last: {last}" if last else "")
            + (f"; last decoding error: {self.errors[-1]}" if self.errors else "")
        )

    def close(self) -> None:
        with contextlib.suppress(Exception):  # the session may be closing already
            self._subscriber.undeclare()


@dataclass(frozen=True)
class NavOutcome:
    """How a :meth:`Robot.nav` goal ended: the task result, the server's result message, and why it failed."""

    result: TaskResult
    detail: NavigateToPoseResult | None
    reason: str

    @property
    def succeeded(self) -> bool:
        return self.result is TaskResult.SUCCEEDED


class Robot:
    """One robot of a running stack (namespace ``namespace``), on its own client session to ``endpoint``."""

    def __init__(self, endpoint: str, namespace: str = "", name: str = "zendock_test_robot") -> None:
        self.endpoint = endpoint
        self.session = open_session(SessionSpec(mode="client", connect=(endpoint,)))
        try:
            self.node = Node(name, self.session, namespace)
        except BaseException:  # a bad namespace: the session must not outlive the refusal
            self.session.close()
            raise
        self._spinner = spin_in_background(self.node)
        try:
            self.navigation = NavigationClient(self.node)
            self._dock_client: ActionClient[Any, Any, Any] = ActionClient(
                self.node, DOCK_ROBOT, topics.DOCK_ROBOT
            )
            self._undock_client: ActionClient[Any, Any, Any] = ActionClient(
                self.node, UNDOCK_ROBOT, topics.UNDOCK_ROBOT
            )
            self._recordings: dict[tuple[str, type[Message] | None], KeyRecording] = {}
            self._publishers: dict[tuple[str, type[Message]], Publisher[Any]] = {}
            self._battery = self.watch(topics.BATTERY_STATUS, BatteryState)
            self._pose = self.watch(topics.POSE2D, Float64MultiArray)
        except BaseException:  # nothing of a half-built handle outlives it
            self.node.shutdown()
            self._spinner.join(5.0)
            self.node.close()
            self.session.close()
            raise

    @property
    def namespace(self) -> str:
        return self.node.namespace

    # -- what the robot says -------------------------------------------------------------------------------
    @property
    def battery(self) -> BatteryState | None:
        """The latest ``battery_status`` (``None`` before the first)."""
        messages = self._battery.messages
        return messages[-1] if messages else None  # type: ignore[return-value]

    @property
    def pose(self) -> list[float] | None:
        """The latest map pose ``[x, y, yaw]`` (``map_to_base_link_pose2d``; ``None`` before the first)."""
        messages = self._pose.messages
        if not messages:
            return None
        data = messages[-1].data  # type: ignore[attr-defined]
        return [float(data[0]), float(data[1]), float(data[2])]

    def watch(self, key: str, msg_type: type[Message] | None = None) -> KeyRecording:
        """Start recording ``key`` (in the robot's namespace; wildcards allowed) now, so a later
        :meth:`wait_for` also sees what arrived in between. Messages are decoded as ``msg_type``, or as
        the type their encoding names; without ``msg_type`` an existing recording of the key is reused."""
        full_key = self.node.key(key)
        recording = next(
            (
                r
                for (k, t), r in self._recordings.items()
                if k == full_key and (msg_type is None or t is msg_type)
            ),
            None,
        )
        if recording is None:
            recording = KeyRecording(self.session, full_key, msg_type)
            self._recordings[(full_key, msg_type)] = recording
        return recording

    def wait_for(
        self,
        key: str,
        predicate: Callable[[Any], bool] = lambda _m: True,
        timeout_s: float = 30.0,
        msg_type: type[Message] | None = None,
        what: str = "matching the condition",
    ) -> Any:
        """The first message on ``key`` satisfying ``predicate``: the latest one already received, or one
        to come. Raises :class:`WaitTimeout` (an ``AssertionError``) after ``timeout_s`` wall seconds,
        listing how many messages came and the last ones."""
        return self.watch(key, msg_type).wait_for(predicate, timeout_s, what)

    # -- acting ----------------------------------------------------------------------------------------------
    def publish(self, key: str, message: Message) -> None:
        """Publish ``message`` on ``key`` (in the robot's namespace), as a zendock publisher does."""
        publisher = self._publishers.get((key, type(message)))
        if publisher is None:
            publisher = self.node.create_publisher(type(message), key)
            self._publishers[(key, type(message))] = publisher
        publisher.publish(message)

    def set_battery(
        self,
        percentage: float,
        drain_scale: float = math.nan,
        frozen: bool = False,
        timeout_s: float = REQUEST_TIMEOUT_S,
    ) -> SetBatteryStateResponse:
        """Put the simulated battery at ``percentage`` (0..1) through ``battery/set_state``."""
        request = SetBatteryStateRequest(percentage=percentage, drain_scale=drain_scale, frozen=frozen)
        return self._call(SET_BATTERY_STATE, topics.BATTERY_SET_STATE, request, timeout_s)

    def sim_state(self, timeout_s: float = REQUEST_TIMEOUT_S) -> SimStateResponse:
        """The simulator's ground truth (``simulator/state``): true pose, collision total, dock contact."""
        return self._call(SIM_STATE, topics.SIM_STATE, SimStateRequest(), timeout_s)

    def _call(self, srv: Any, name: str, request: Message, timeout_s: float) -> Any:
        """A blocking request, retried while nobody answers (a service may still be declaring it)."""
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                return self.node.call(
                    srv, name, request, timeout_s=min(5.0, max(deadline - time.monotonic(), 0.5))
                )
            except ServiceUnavailable as exc:
                if time.monotonic() >= deadline:
                    raise WaitTimeout(
                        f"{self.node.key(name)}: no answer within {timeout_s:g} s ({exc})"
                    ) from None
                time.sleep(0.2)  # nobody declared it yet: ask again shortly, not in a tight loop

    def dock(
        self, dock_id: str | None = None, timeout_s: float = 300.0, server_timeout_s: float = SERVER_TIMEOUT_S
    ) -> DockRobotResult:
        """Send a ``dock_robot`` goal (the nearest dock without ``dock_id``) and wait for its result.

        Returns the result (``success``, ``error_code``, ``num_retries``) however the goal ended; raises
        :class:`WaitTimeout` when no docking service answers, the goal is refused, or there is no result
        within ``timeout_s`` (the goal is then cancelled, so the robot stops).
        """
        goal = DockRobotGoal(use_dock_id=True, dock_id=dock_id or "")
        return self._run_action(self._dock_client, goal, timeout_s, server_timeout_s)

    def undock(
        self, timeout_s: float = 60.0, server_timeout_s: float = SERVER_TIMEOUT_S
    ) -> UndockRobotResult:
        """Send an ``undock_robot`` goal and wait for its result (as :meth:`dock`)."""
        return self._run_action(self._undock_client, UndockRobotGoal(), timeout_s, server_timeout_s)

    def _run_action(
        self, client: ActionClient[Any, Any, Any], goal: Message, timeout_s: float, server_timeout_s: float
    ) -> Any:
        if not client.server_ready(timeout_s=server_timeout_s):
            raise WaitTimeout(
                f"no {client.name} server in namespace {self.namespace!r} within {server_timeout_s:g} s"
            )
        done = threading.Event()
        handle: ClientGoal[Any, Any] = client.send_goal(goal, on_done=lambda _h: done.set())
        if not done.wait(timeout_s):
            client.cancel_goal(handle)
            done.wait(5.0)
            with client.lock:
                raise WaitTimeout(
                    f"{client.name}: no result within {timeout_s:g} s (status {handle.status.name}, "
                    f"last feedback {handle.feedback!r}); the goal was cancelled"
                )
        with client.lock:
            if handle.accepted is False:
                raise WaitTimeout(f"{client.name}: the goal was refused: {handle.rejection}")
            if handle.error or handle.result is None:
                raise WaitTimeout(f"{client.name}: no result: {handle.error or 'empty reply'}")
            return handle.result

    def nav(
        self,
        x: float,
        y: float,
        yaw: float,
        timeout_s: float = 120.0,
        server_timeout_s: float = SERVER_TIMEOUT_S,
    ) -> NavOutcome:
        """Drive to the map pose ``(x, y, yaw)`` with the planner; returns how the goal ended.

        Raises :class:`WaitTimeout` when no planner answers, or the goal has not ended within ``timeout_s``
        (it is then cancelled, and the message gives the last feedback).
        """
        nav = self.navigation
        if not nav.wait_until_active(server_timeout_s):
            raise WaitTimeout(
                f"no navigation server in namespace {self.namespace!r} within {server_timeout_s:g} s"
            )
        nav.go_to_pose(Pose2D(x, y, yaw))
        deadline = time.monotonic() + timeout_s
        while not nav.is_task_complete():
            if time.monotonic() >= deadline:
                feedback = nav.get_feedback()
                nav.cancel_task()
                raise WaitTimeout(
                    f"navigate_to_pose ({x:g}, {y:g}, {yaw:g}) did not end within {timeout_s:g} s; "
                    f"last feedback {feedback!r}; the goal was cancelled"
                )
            time.sleep(0.05)  # polls the client's state; the node's thread fills it in
        return NavOutcome(nav.get_result(), nav.get_result_detail(), nav.failure_reason())

    # -- end -----------------------------------------------------------------------------------------------------
    def close(self) -> None:
        """Stop the node's thread, undeclare every subscriber, close the node and the session."""
        self.node.shutdown()
        self._spinner.join(5.0)
        for recording in self._recordings.values():
            recording.close()
        self.node.close()
        self.session.close()


def is_charging(battery: BatteryState) -> bool:
    """``battery_status`` says the robot charges (or is full on the dock)."""
    return battery.power_supply_status in (
        BatteryState.POWER_SUPPLY_STATUS_CHARGING,
        BatteryState.POWER_SUPPLY_STATUS_FULL,
    )


__all__ = ["KeyRecording", "NavOutcome", "Robot", "WaitTimeout", "decode_sample", "is_charging"]
