"""``zendock nav X Y YAW``: send the robot to a map pose through the planner's ``navigate_to_pose`` action.

Prints the distance remaining as the robot goes, then the outcome. Exit codes: 0 the goal SUCCEEDED;
1 it failed, was canceled or rejected, timed out (``--timeout``, the goal is then canceled), or no
router or navigation server answered; 2 bad arguments; 130 interrupted (the goal is canceled first).
``--connect`` (repeatable) falls back to ``ZENDOCK_CONNECT``, then ``ZENOH_CONNECT``, then the default
router; ``--namespace`` to ``ZENDOCK_NAMESPACE``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, TextIO

from deploy.options import add_connect_option
from shared.bus_env import connect_from_env

if TYPE_CHECKING:
    from shared.navigation import NavigationClient

#: How long to wait for the router before giving up.
CONNECT_TIMEOUT_S = 3.0
#: How long a canceled goal may take to end before the command gives up on it.
CANCEL_WAIT_S = 5.0
#: Feedback lines at most this often.
PRINT_PERIOD_S = 0.5


def _endpoints(flags: Sequence[str] | None) -> tuple[str, ...]:
    from shared.session import DEFAULT_ROUTER_ENDPOINT  # noqa: PLC0415 - keep CLI start-up light

    return tuple(flags) if flags else connect_from_env() or (DEFAULT_ROUTER_ENDPOINT,)


def run_nav(
    x: float,
    y: float,
    yaw: float,
    *,
    connect: tuple[str, ...],
    namespace: str,
    timeout_s: float,
    server_timeout_s: float = 10.0,
    out: TextIO | None = None,
    err: TextIO | None = None,
) -> int:
    """Drive to ``(x, y, yaw)`` and report; returns the exit code (see the module docstring)."""
    out = out or sys.stdout
    err = err or sys.stderr
    import zenoh  # noqa: PLC0415

    from shared.action import spin_in_background  # noqa: PLC0415
    from shared.geometry import Pose2D  # noqa: PLC0415
    from shared.navigation import NavigationClient  # noqa: PLC0415
    from shared.node import Node  # noqa: PLC0415
    from shared.session import SessionSpec, open_session  # noqa: PLC0415

    spec = SessionSpec(
        mode="client",
        connect=connect,
        overrides=(
            ("connect/timeout_ms", json.dumps(int(CONNECT_TIMEOUT_S * 1000))),
            ("connect/exit_on_failure", "true"),
        ),
    )
    try:
        session = open_session(spec)
    except zenoh.ZError:
        print(
            f"zendock nav: cannot reach a Zenoh router at {', '.join(connect)} within "
            f"{CONNECT_TIMEOUT_S:g} s; is the stack up?",
            file=err,
        )
        return 1
    with session:
        node = Node("zendock_nav", session, namespace)
        spin_in_background(node)
        nav = NavigationClient(node)
        try:
            if not nav.wait_until_active(server_timeout_s):
                where = f"namespace {namespace!r}" if namespace else "the root namespace"
                print(
                    f"zendock nav: no navigation server in {where} within {server_timeout_s:g} s "
                    "(is the planner running?)",
                    file=err,
                )
                return 1
            goal = Pose2D(x, y, yaw)
            nav.go_to_pose(goal)
            print(f"goal ({x:.2f}, {y:.2f}, {yaw:.2f}) sent", file=out, flush=True)
            return _follow(nav, timeout_s, out, err)
        except KeyboardInterrupt:
            nav.cancel_task()
            _wait_done(nav, CANCEL_WAIT_S)
            print("zendock nav: interrupted, goal canceled", file=err)
            return 130
        finally:
            node.shutdown()
            node.close()


def _follow(nav: NavigationClient, timeout_s: float, out: TextIO, err: TextIO) -> int:
    from shared.navigation import TaskResult  # noqa: PLC0415

    deadline = time.monotonic() + timeout_s
    last_print = -math.inf
    last_shown = None
    while not nav.is_task_complete():
        if time.monotonic() > deadline:
            nav.cancel_task()
            _wait_done(nav, CANCEL_WAIT_S)
            print(f"zendock nav: goal not reached within {timeout_s:g} s: canceled", file=err)
            return 1
        feedback = nav.get_feedback()
        if (
            feedback is not None
            and feedback is not last_shown
            and time.monotonic() - last_print >= PRINT_PERIOD_S
        ):
            last_shown, last_print = feedback, time.monotonic()
            recoveries = (
                f", {feedback.number_of_recoveries} recoveries" if feedback.number_of_recoveries else ""
            )
            print(
                f"distance remaining {feedback.distance_remaining:6.2f} m, "
                f"about {feedback.estimated_time_remaining.to_sec():5.1f} s{recoveries}",
                file=out,
                flush=True,
            )
        time.sleep(0.05)
    result = nav.get_result()
    if result is TaskResult.SUCCEEDED:
        print("goal reached", file=out, flush=True)
        return 0
    reason = nav.failure_reason() or "no reason given"
    print(f"zendock nav: goal {result.name.lower()}: {reason}", file=err)
    return 1


def _wait_done(nav: NavigationClient, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while not nav.is_task_complete() and time.monotonic() < deadline:
        time.sleep(0.05)


def _nav(args: argparse.Namespace) -> int:
    from shared.names import normalise_namespace  # noqa: PLC0415

    values = (args.x, args.y, args.yaw)
    if not all(math.isfinite(v) for v in values):
        print(f"zendock nav: X Y YAW must be finite numbers, got {list(values)}", file=sys.stderr)
        return 2
    if not args.timeout > 0:
        print(f"zendock nav: --timeout must be positive, got {args.timeout:g}", file=sys.stderr)
        return 2
    raw_namespace = os.environ.get("ZENDOCK_NAMESPACE", "") if args.namespace is None else args.namespace
    try:
        namespace = normalise_namespace(raw_namespace)
    except ValueError as exc:
        print(f"zendock nav: --namespace: {exc}", file=sys.stderr)
        return 2
    return run_nav(
        args.x,
        args.y,
        args.yaw,
        connect=_endpoints(args.connect),
        namespace=namespace,
        timeout_s=args.timeout,
        server_timeout_s=args.server_timeout,
    )


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "nav",
        help="drive to a map pose with the planner (X Y YAW), printing the distance remaining",
        description="Send a navigate_to_pose goal and follow it to the end. Exit 0 when it succeeds.",
    )
    parser.add_argument("x", type=float, help="goal x in the map frame, metres")
    parser.add_argument("y", type=float, help="goal y in the map frame, metres")
    parser.add_argument("yaw", type=float, help="goal heading, radians")
    parser.add_argument(
        "--namespace", default=None, metavar="NS", help="robot namespace (env ZENDOCK_NAMESPACE)"
    )
    add_connect_option(parser)
    parser.add_argument(
        "--timeout",
        type=float,
        default=300.0,
        metavar="S",
        help="cancel and fail if the goal is not reached within S seconds (default 300)",
    )
    parser.add_argument(
        "--server-timeout",
        type=float,
        default=10.0,
        metavar="S",
        help="wait this long for the navigation server (default 10)",
    )
    parser.set_defaults(func=_nav)
