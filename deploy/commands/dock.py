"""``zendock dock [DOCK_ID]`` and ``zendock undock``: the docking service's actions from the command line.

Both send one goal to the docking service (``dock_robot`` / ``undock_robot`` in ``--namespace``), print
each change of the feedback as it comes (time on the service's clock, state, retries; for ``dock`` the
distance to the dock from ``map_to_base_link_pose2d``, and a line at least every second) and the
result, and exit 0 on success (``dock``: once the battery says CHARGING, its last line ``charging``), 1 on failure or when no docking service answers, 130 when interrupted (the goal
is cancelled first: the robot stops). Endpoints come from ``--connect`` (repeatable), else
``ZENDOCK_CONNECT``, else ``ZENOH_CONNECT``, else the default router; the namespace from
``--namespace``, else ``ZENDOCK_NAMESPACE``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TextIO

import zenoh

from deploy.options import add_bus_options
from deploy.paths import REPO_ROOT
from deploy.progress import dock_line
from deploy.world_names import world_argument
from shared import topics
from shared.action import ActionClient, ClientGoal, spin_in_background
from shared.bus_env import connect_from_env
from shared.config_errors import ConfigError
from shared.geometry import Pose2D
from shared.interface_types import ActionType, GoalStatusCode
from shared.interfaces.docking import (
    DOCK_ROBOT,
    UNDOCK_ROBOT,
    DockRobotFeedback,
    DockRobotGoal,
    DockRobotResult,
    UndockRobotGoal,
)
from shared.messages import BatteryState, Float64MultiArray, Header, Pose, PoseStamped
from shared.names import normalise_namespace, topic_key
from shared.node import Node
from shared.schema import MessageError
from shared.session import DEFAULT_ROUTER_ENDPOINT, SessionSpec, open_session
from shared.waiting import wait_interruptibly
from shared.world import load_world

EXIT_OK, EXIT_FAILED, EXIT_INTERRUPTED = 0, 1, 130
#: After the dock_robot goal succeeded, how long the battery has to say CHARGING (wall seconds).
CHARGING_WAIT_S = 15.0
DEFAULT_WORLD = "deploy/worlds/seed_room.yaml"

#: ``zendock dock`` prints a line at least this often (wall seconds) while the robot docks.
DOCK_PROGRESS_PERIOD_S = 1.0


def _constant_names(cls: type, exclude: tuple[str, ...] = ()) -> dict[int, str]:
    return {v: k for k, v in vars(cls).items() if k.isupper() and isinstance(v, int) and k not in exclude}


#: Feedback ``state`` and result ``error_code`` values by name, from the interface's constants.
STATE_NAMES = _constant_names(DockRobotFeedback)
ERROR_NAMES = _constant_names(DockRobotResult)


def endpoints(flags: list[str] | None) -> tuple[str, ...]:
    """``--connect``, else the environment as every zendock process reads it (:mod:`shared.bus_env`)."""
    return tuple(flags) if flags else connect_from_env() or (DEFAULT_ROUTER_ENDPOINT,)


class RouterUnreachable(Exception):
    """No Zenoh router answered at the endpoints within the connect timeout."""


def client_session(args: argparse.Namespace) -> zenoh.Session:
    """A client session to the router at the command's endpoints (``RouterUnreachable`` when none answers)."""
    spec = SessionSpec(
        mode="client",
        connect=endpoints(args.connect),
        config_file=getattr(args, "zenoh_config", None) or os.environ.get("ZENDOCK_ZENOH_CONFIG") or None,
        overrides=(
            ("connect/timeout_ms", json.dumps(int(args.connect_timeout * 1000))),
            ("connect/exit_on_failure", "true"),
        ),
    )
    try:
        return open_session(spec)
    except ValueError as exc:  # the config file
        raise ConfigError(f"--zenoh-config: {exc}") from None
    except zenoh.ZError as exc:
        detail = str(exc).split(" at /")[0]
        raise RouterUnreachable(
            f"cannot reach a Zenoh router at {', '.join(spec.connect)} ({detail}); is the stack up?"
        ) from None


def namespace_arg(args: argparse.Namespace) -> str:
    raw = os.environ.get("ZENDOCK_NAMESPACE", "") if args.namespace is None else args.namespace
    try:
        return normalise_namespace(raw)
    except ValueError as exc:
        raise ConfigError(f"--namespace: {exc}") from None


def describe_dock_feedback(
    feedback: DockRobotFeedback, distance_m: float | None = None
) -> tuple[object, str]:
    """What changed (state, retries) and the line to print for it (with the distance to the dock, if known)."""
    state = STATE_NAMES.get(feedback.state, str(feedback.state))
    line = dock_line(
        docking_time_s=feedback.docking_time.to_sec(),
        state=state,
        retries=feedback.num_retries,
        distance_m=distance_m,
    )
    return (feedback.state, feedback.num_retries), line


class Approach:
    """The robot's pose (``map_to_base_link_pose2d``) and charging state (``battery_status``) while it docks.

    Zenoh callbacks only store the latest values; the distance is to ``dock`` (a map pose), or, without
    one, to the nearest of ``docks`` from where the robot first stood.
    """

    def __init__(
        self, session: zenoh.Session, namespace: str, dock: Pose2D | None, docks: list[Pose2D]
    ) -> None:
        self._dock, self._docks = dock, docks
        self._pose: Pose2D | None = None
        self.charging = threading.Event()
        self._subscribers = [
            session.declare_subscriber(topic_key(namespace, topics.POSE2D), self._on_pose),
            session.declare_subscriber(topic_key(namespace, topics.BATTERY_STATUS), self._on_battery),
        ]

    def _on_pose(self, sample: zenoh.Sample) -> None:
        with contextlib.suppress(MessageError, ValueError):
            data = Float64MultiArray.decode(sample.payload.to_bytes()).data
            self._pose = Pose2D(float(data[0]), float(data[1]), float(data[2]))
            if self._dock is None and self._docks:
                here = self._pose
                self._dock = min(self._docks, key=lambda d: math.hypot(d.x - here.x, d.y - here.y))

    def _on_battery(self, sample: zenoh.Sample) -> None:
        with contextlib.suppress(MessageError):
            status = BatteryState.decode(sample.payload.to_bytes()).power_supply_status
            if status in (BatteryState.POWER_SUPPLY_STATUS_CHARGING, BatteryState.POWER_SUPPLY_STATUS_FULL):
                self.charging.set()
            else:
                self.charging.clear()

    def distance_m(self) -> float | None:
        pose, dock = self._pose, self._dock
        return None if pose is None or dock is None else math.hypot(dock.x - pose.x, dock.y - pose.y)

    def close(self) -> None:
        for sub in self._subscribers:
            with contextlib.suppress(Exception):
                sub.undeclare()


def _dock_poses(args: argparse.Namespace) -> tuple[Pose2D | None, list[Pose2D]]:
    """The dock to measure the distance to (``--pose``, or DOCK_ID in the world file), and all the world's docks.

    The world file is ``--world``, else ``ZENDOCK_WORLD`` (the stack's), else the default stack's; without
    a readable one the lines go without a distance.
    """
    if args.pose is not None:
        return Pose2D.from_seq(args.pose), []
    path = Path(args.world or os.environ.get("ZENDOCK_WORLD") or DEFAULT_WORLD)
    if not path.is_absolute():
        path = (REPO_ROOT / path) if not path.is_file() else path
    try:
        world = load_world(path)
    except (ConfigError, OSError, ValueError):
        return None, []
    docks = {d.id: d.pose2d for d in world.docks}
    if args.dock_id:
        return docks.get(args.dock_id), []
    return None, list(docks.values())


def run_action(
    session: zenoh.Session,
    namespace: str,
    action: ActionType[Any, Any, Any],
    action_name: str,
    goal: Any,
    out: TextIO,
    *,
    describe_feedback: Callable[[Any], tuple[object, str]] | None = None,
    server_timeout_s: float = 10.0,
    timeout_s: float | None = None,
    repeat_every_s: float | None = None,
) -> tuple[int, ClientGoal[Any, Any] | None]:
    """Send ``goal``, print feedback changes, wait for the result; returns the exit code and the goal.

    ``describe_feedback`` turns a feedback message into ``(what changed, line)``; a line is printed when
    what changed differs from the previous message's, and, with ``repeat_every_s``, at least that often:
    the latest feedback described again (its distance then current) whenever no line came for that long,
    whether or not new feedback arrived.
    """
    node = Node("zendock_cli", session, namespace)
    thread = spin_in_background(node)
    client: ActionClient[Any, Any, Any] = ActionClient(node, action, action_name)
    try:
        if not client.server_ready(timeout_s=server_timeout_s):
            where = f"namespace {namespace!r}" if namespace else "the root namespace"
            print(f"no {action_name} server in {where} (is the docking service running?)", file=sys.stderr)
            return EXIT_FAILED, None
        done = threading.Event()
        lines = _FeedbackLines(describe_feedback, out, repeat_every_s)
        handle = client.send_goal(goal, on_feedback=lines.feedback, on_done=lambda _h: done.set())
        try:
            finished = _wait_repeating(done, timeout_s, lines)
        except KeyboardInterrupt:
            print("interrupted: cancelling", file=sys.stderr)
            client.cancel_goal(handle)
            done.wait(5.0)
            return EXIT_INTERRUPTED, handle
        if not finished:
            print(f"no result within {timeout_s:g} s: cancelling", file=sys.stderr)
            client.cancel_goal(handle)
            done.wait(5.0)
            return EXIT_FAILED, handle
        return (EXIT_OK if _succeeded(handle) else EXIT_FAILED), handle
    finally:
        node.shutdown()
        thread.join(5.0)
        node.close()


class _FeedbackLines:
    """The lines an action's feedback makes: one on each change, and the latest again once ``repeat_every_s``
    has passed without a line (:meth:`repeat`, from the waiting thread). Feedback comes on the node's thread."""

    def __init__(
        self,
        describe: Callable[[Any], tuple[object, str]] | None,
        out: TextIO,
        repeat_every_s: float | None,
    ) -> None:
        self._describe = describe
        self._out = out
        self.repeat_every_s = repeat_every_s
        self._lock = threading.Lock()
        self._latest: Any = None
        self._change: object = _NOTHING
        self._printed_at = -math.inf

    def feedback(self, feedback: Any) -> None:
        if self._describe is None:
            return
        change, line = self._describe(feedback)
        with self._lock:
            self._latest = feedback
            if change != self._change:
                self._change = change
                self._print(line)

    def repeat(self) -> None:
        """The latest feedback's line again, when none was printed for ``repeat_every_s``."""
        if self._describe is None or self.repeat_every_s is None:
            return
        with self._lock:
            if self._latest is None or time.monotonic() - self._printed_at < self.repeat_every_s:
                return
            self._print(self._describe(self._latest)[1])

    def next_due_s(self) -> float:
        """When (monotonic) :meth:`repeat` next has a line to print, if no other comes first."""
        period = self.repeat_every_s or math.inf
        with self._lock:
            return time.monotonic() + period if self._latest is None else self._printed_at + period

    def _print(self, line: str) -> None:
        print(line, file=self._out, flush=True)
        self._printed_at = time.monotonic()


_NOTHING = object()


def _wait_repeating(done: threading.Event, timeout_s: float | None, lines: _FeedbackLines) -> bool:
    """Wait for ``done`` (at most ``timeout_s``), repeating the progress line as it falls due."""
    if lines.repeat_every_s is None:
        return wait_interruptibly(done, timeout_s)
    deadline = math.inf if timeout_s is None else time.monotonic() + timeout_s
    while True:
        # until the next line falls due (a period from the last, or a period on while nothing came yet)
        wake = min(deadline, max(lines.next_due_s(), time.monotonic() + 0.01))
        if wait_interruptibly(done, max(0.0, min(wake - time.monotonic(), lines.repeat_every_s))):
            return True
        if time.monotonic() >= deadline:
            return False
        lines.repeat()


def _succeeded(handle: ClientGoal[Any, Any]) -> bool:
    return (
        handle.status == GoalStatusCode.SUCCEEDED
        and handle.result is not None
        and bool(handle.result.success)
    )


def _outcome(handle: ClientGoal[Any, Any]) -> str:
    if handle.accepted is False:
        return f"rejected: {handle.rejection}"
    if handle.error:
        return f"failed: {handle.error}"
    result = handle.result
    code = getattr(result, "error_code", 0)
    detail = f" (error {code} {ERROR_NAMES.get(code, '')})".rstrip() if code else ""
    return f"{handle.status.name.lower()}{detail}"


def dock_main(args: argparse.Namespace) -> int:
    namespace = namespace_arg(args)
    goal = DockRobotGoal(
        use_dock_id=args.pose is None,
        dock_id=args.dock_id or "",
        navigate_to_staging_pose=not args.no_staging,
        max_staging_time=args.max_staging_time,
    )
    if args.pose is not None:
        if not all(math.isfinite(v) for v in args.pose):
            raise ConfigError(f"--pose: expected three finite numbers, got {args.pose}")
        goal.dock_pose = PoseStamped(
            Header(frame_id=topics.MAP_FRAME), Pose.from_pose2d(Pose2D.from_seq(args.pose))
        )
    target = (
        f"dock {args.dock_id!r}" if args.dock_id else ("the given pose" if args.pose else "the nearest dock")
    )
    print(f"docking at {target}", flush=True)
    dock, docks = _dock_poses(args)
    # A line on every change of state and at least every second as the robot closes in: a long drive to the
    # staging pose is not a silence.
    repeat_every_s = DOCK_PROGRESS_PERIOD_S
    try:
        with client_session(args) as session:
            approach = Approach(session, namespace, dock, docks)
            try:
                code, handle = run_action(
                    session,
                    namespace,
                    DOCK_ROBOT,
                    topics.DOCK_ROBOT,
                    goal,
                    sys.stdout,
                    describe_feedback=lambda fb: describe_dock_feedback(fb, approach.distance_m()),
                    server_timeout_s=args.server_timeout,
                    timeout_s=args.timeout,
                    repeat_every_s=repeat_every_s,
                )
                charging = code == EXIT_OK and approach.charging.wait(CHARGING_WAIT_S)
            finally:
                approach.close()
    except RouterUnreachable as exc:
        print(f"zendock dock: {exc}", file=sys.stderr)
        return EXIT_FAILED
    if handle is not None:
        retries = getattr(handle.result, "num_retries", 0)
        suffix = f" after {retries} retr{'y' if retries == 1 else 'ies'}" if retries else ""
        print(("docked" if code == EXIT_OK else f"docking {_outcome(handle)}") + suffix, flush=True)
    if code == EXIT_OK:
        if not charging:
            print(f"the battery does not report charging {CHARGING_WAIT_S:g} s after docking", flush=True)
            return EXIT_FAILED
        print("charging", flush=True)
    return code


def undock_main(args: argparse.Namespace) -> int:
    namespace = namespace_arg(args)
    goal = UndockRobotGoal(dock_type=args.dock_type, max_undocking_time=args.max_undocking_time)
    print("undocking", flush=True)
    try:
        with client_session(args) as session:
            code, handle = run_action(
                session,
                namespace,
                UNDOCK_ROBOT,
                topics.UNDOCK_ROBOT,
                goal,
                sys.stdout,
                server_timeout_s=args.server_timeout,
                timeout_s=args.timeout,
            )
    except RouterUnreachable as exc:
        print(f"zendock undock: {exc}", file=sys.stderr)
        return EXIT_FAILED
    if handle is not None:
        print("undocked" if code == EXIT_OK else f"undocking {_outcome(handle)}", flush=True)
    return code


def add_connection_flags(group: argparse._ActionsContainer) -> None:
    """Where a command finds the bus: namespace, endpoints, connect timeout, Zenoh config (dock, health)."""
    add_bus_options(group)
    group.add_argument(
        "--zenoh-config",
        default=None,
        metavar="FILE",
        help="Zenoh json5 config, e.g. a secure profile user's (env ZENDOCK_ZENOH_CONFIG)",
    )


def _bus_flags(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("bus")
    add_connection_flags(group)
    group.add_argument(
        "--server-timeout",
        type=float,
        default=10.0,
        metavar="S",
        help="wait this long for the docking service to answer (default 10)",
    )
    group.add_argument(
        "--timeout",
        type=float,
        default=None,
        metavar="S",
        help="cancel and fail if there is no result after S wall seconds (default: wait)",
    )


def register(subparsers: argparse._SubParsersAction) -> None:
    dock = subparsers.add_parser(
        "dock",
        help="dock the robot (dock_robot action); exit 0 once charging",
        description="Send a dock_robot goal, print its feedback, exit 0 on success.",
    )
    dock.add_argument(
        "dock_id", nargs="?", default="", metavar="DOCK_ID", help="dock id (default: the nearest dock)"
    )
    dock.add_argument(
        "--pose",
        type=float,
        nargs=3,
        metavar=("X", "Y", "YAW"),
        help="dock at this map pose instead of a database dock",
    )
    dock.add_argument(
        "--world",
        type=world_argument,
        default=None,
        metavar="FILE",
        help="world file the dock poses are read from, for the distance shown "
        "(env ZENDOCK_WORLD; default deploy/worlds/seed_room.yaml)",
    )
    dock.add_argument(
        "--no-staging", action="store_true", help="the robot is already at the staging pose: skip the planner"
    )
    dock.add_argument(
        "--max-staging-time",
        type=float,
        default=1000.0,
        metavar="S",
        help="time limit to reach the staging pose, seconds (default 1000)",
    )
    _bus_flags(dock)
    dock.set_defaults(func=dock_main)
    undock = subparsers.add_parser(
        "undock",
        help="undock the robot (undock_robot action); exit 0 once off the dock",
        description="Send an undock_robot goal, exit 0 on success.",
    )
    undock.add_argument("--dock-type", default="", help="dock type (default: any)")
    undock.add_argument(
        "--max-undocking-time",
        type=float,
        default=30.0,
        metavar="S",
        help="time limit to back off the dock, seconds (default 30)",
    )
    _bus_flags(undock)
    undock.set_defaults(func=undock_main)
