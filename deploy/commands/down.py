"""``zendock down``: stop every service of a project and its supervisor, and remove the runtime state.

With a live supervisor (``up -d``, a foreground ``up`` or the Python API) it asks it to stop everything;
when the supervisor died, it stops the process groups recorded in ``state.json`` itself. Logs are kept.
"""

from __future__ import annotations

import argparse
import sys
import time

from deploy.launcher.process import is_alive
from deploy.launcher.project import add_project_options, resolve_project
from deploy.launcher.runtime import (
    ControlError,
    RuntimePaths,
    clear_runtime,
    process_matches,
    request,
    stop_orphans,
    supervisor_info,
)

DOWN_TIMEOUT_S = 180.0


def bring_down(paths: RuntimePaths, timeout_s: float = DOWN_TIMEOUT_S) -> list[str]:
    """Stop the project; returns the names of the services that were up."""
    info = supervisor_info(paths)
    if info is None:
        stopped = stop_orphans(paths, grace_s=5.0)
        clear_runtime(paths)
        return stopped
    reply = request(paths, "down", timeout_s=timeout_s)
    supervisor = process_matches(info.get("pid"), info.get("create_time"))
    deadline = time.monotonic() + 10.0
    while supervisor is not None and is_alive(supervisor) and time.monotonic() < deadline:
        time.sleep(0.05)
    return [item["name"] for item in reply.get("services", [])]


def main(args: argparse.Namespace) -> int:
    name, paths, _ = resolve_project(args)
    if supervisor_info(paths) is None and not paths.state_file.exists():
        print(f"{name}: nothing is up")
        return 0
    try:
        stopped = bring_down(paths, args.timeout)
    except ControlError as exc:
        print(f"zendock down: {exc}", file=sys.stderr)
        return 1
    for service in stopped:
        print(f"{service}: stopped")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("down", help="stop the stack and remove its runtime state")
    add_project_options(parser)
    parser.add_argument(
        "-t", "--timeout", type=float, default=DOWN_TIMEOUT_S, metavar="SECONDS", help="(default 180)"
    )
    parser.set_defaults(func=main)
