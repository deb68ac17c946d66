"""``zendock ps``: the services of a project, their state, pid, restarts and health."""

from __future__ import annotations

import argparse
import json
import sys

from deploy.launcher.durations import format_duration
from deploy.launcher.project import add_project_options, resolve_project
from deploy.launcher.runtime import (
    ControlError,
    RuntimePaths,
    process_matches,
    recorded_statuses,
    request,
    supervisor_info,
)
from deploy.launcher.status import ServiceStatus


def current_statuses(paths: RuntimePaths) -> tuple[list[ServiceStatus], bool]:
    """From the live supervisor, else from the last ``state.json`` (``False``: the supervisor is gone)."""
    if supervisor_info(paths) is not None:
        try:
            reply = request(paths, "ps")
            return [ServiceStatus.from_dict(item) for item in reply["services"]], True
        except ControlError:
            pass
    statuses = []
    for status in recorded_statuses(paths):
        if status.pid is not None and process_matches(status.pid, status.pid_create_time) is None:
            status = ServiceStatus(status.name, "exited", None, status.restarts, "none", "exited", None, "gone")
        statuses.append(status)
    return statuses, False


def format_table(statuses: list[ServiceStatus]) -> str:
    """One row per service; a fleet's services grouped by namespace (robot), each group under its name."""
    namespaces = list(dict.fromkeys(sorted(s.namespace for s in statuses)))
    grouped = len(namespaces) > 1
    rows: list[tuple[str, ...]] = [("NAME", "STATE", "PID", "RESTARTS", "HEALTH", "DETAIL")]
    for namespace in namespaces:
        if grouped and namespace != namespaces[0]:
            rows.append((f"{namespace}/",))
        for s in (s for s in statuses if s.namespace == namespace):
            detail = s.detail or (f"up {format_duration(round(s.uptime_s))}" if s.uptime_s is not None else "")
            if s.members:  # one process: its services start, crash and restart together
                detail = f"{detail}  [group: {', '.join(s.members)}]".strip()
            name = f"  {s.name}" if grouped and namespace != namespaces[0] else s.name
            rows.append((name, s.state, str(s.pid or "-"), str(s.restarts), s.health, detail))
    table = [row for row in rows if len(row) == 6]
    widths = [max(len(row[i]) for row in table) for i in range(5)]
    return "\n".join(
        row[0] if len(row) == 1
        else "  ".join([*(cell.ljust(w) for cell, w in zip(row[:5], widths, strict=True)), row[5]]).rstrip()
        for row in rows
    )


def main(args: argparse.Namespace) -> int:
    _, paths, _ = resolve_project(args)
    statuses, live = current_statuses(paths)
    if args.services:
        statuses = [s for s in statuses if s.name in args.services]
    if statuses and not live:
        print("zendock ps: the supervisor is not running (stale state); `zendock down` cleans up", file=sys.stderr)
    if args.json:
        print(json.dumps([s.ps_json() for s in statuses]))
    else:
        print(format_table(statuses))
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("ps", help="list the services and their state")
    add_project_options(parser)
    parser.add_argument("--json", action="store_true", help='a JSON array of {"name","state","pid","restarts","health","exit_code","started_at","members",'
                             '"namespace"}')
    parser.add_argument("services", nargs="*", metavar="SERVICE")
    parser.set_defaults(func=main)
