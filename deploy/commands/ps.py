"""``zendock ps``: the services of a project, their state, pid, restarts and health."""

from __future__ import annotations

import argparse
import io
import json
import sys

from rich.console import Console
from rich.table import Table
from rich.text import Text

from deploy.launcher.durations import format_duration
from deploy.launcher.project import add_project_options, find_stack_file, no_stack_file, resolve_project
from deploy.launcher.runtime import (
    ControlError,
    RuntimePaths,
    process_matches,
    recorded_statuses,
    request,
    supervisor_info,
)
from deploy.launcher.status import ServiceStatus
from shared.config_errors import ConfigError
from shared.suggestions import no_such


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
            status = ServiceStatus(
                status.name, "exited", None, status.restarts, "none", "exited", None, "gone"
            )
        statuses.append(status)
    return statuses, False


COLUMNS = ("NAME", "STATE", "PID", "RESTARTS", "HEALTH", "DETAIL")


def state_word(status: ServiceStatus) -> str:
    """The table's STATE: a step that ran to its end (the map, exit 0) is ``done``, not ``exited`` like a
    crash (``ps --json`` keeps Compose's ``exited`` with its ``exit_code``)."""
    return "done" if status.state == "exited" and status.exit_code == 0 else status.state


def ps_table(statuses: list[ServiceStatus]) -> Table:
    """One row per service; a fleet's services grouped by namespace (robot), each group under its name."""
    namespaces = list(dict.fromkeys(sorted(s.namespace for s in statuses)))
    grouped = len(namespaces) > 1
    table = Table(box=None, show_edge=False, pad_edge=False, padding=(0, 2, 0, 0), header_style="")
    for column in COLUMNS:
        table.add_column(column, no_wrap=True)
    for namespace in namespaces:
        nested = grouped and namespace != namespaces[0]
        if nested:
            table.add_row(Text(f"{namespace}/"))
        for s in (s for s in statuses if s.namespace == namespace):
            detail = s.detail or (
                f"up {format_duration(round(s.uptime_s))}" if s.uptime_s is not None else ""
            )
            if s.last_exit and s.last_exit not in detail:  # running again: why it stopped last time
                detail = f"{detail} (last: {s.last_exit})".strip()
            if s.standby:  # what a restart would start from
                detail = f"{detail}, warm standby {s.standby}".strip(", ")
            if s.members:  # one process: its services start, crash and restart together
                detail = f"{detail}  [group: {', '.join(s.members)}]".strip()
            name = f"  {s.name}" if nested else s.name
            table.add_row(
                *(
                    Text(cell)
                    for cell in (name, state_word(s), str(s.pid or "-"), str(s.restarts), s.health, detail)
                )
            )
    return table


def format_table(statuses: list[ServiceStatus]) -> str:
    """The table as plain text, one line per row however wide (``zendock ps | grep`` keeps working)."""
    console = Console(file=io.StringIO(), width=100_000, color_system=None, highlight=False, markup=False)
    console.print(ps_table(statuses))
    return "\n".join(line.rstrip() for line in console.file.getvalue().splitlines())  # type: ignore[attr-defined]


def main(args: argparse.Namespace) -> int:
    _, paths, stack = resolve_project(args)
    stack_file = find_stack_file(args)
    if (stack_file is None or not stack_file.is_file()) and not paths.state_dir.exists():
        raise no_stack_file(
            stack_file
        )  # outside a project: nothing to list, and an empty table would hide it
    statuses, live = current_statuses(paths)
    if args.services:
        known = list(
            dict.fromkeys([*(stack.services if stack is not None else ()), *(s.name for s in statuses)])
        )
        unknown = [name for name in args.services if name not in known]
        if unknown and known:  # a name the project has no service by: an empty table would hide the typo
            raise ConfigError(no_such("service", unknown, known))
        statuses = [s for s in statuses if s.name in args.services]
    if statuses and not live:
        print(
            "zendock ps: the supervisor is not running (stale state); `zendock down` cleans up",
            file=sys.stderr,
        )
    if args.json:
        print(json.dumps([s.ps_json() for s in statuses]))
    else:
        print(format_table(statuses))
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("ps", help="list the services and their state")
    add_project_options(parser)
    parser.add_argument(
        "--json",
        action="store_true",
        help='a JSON array of {"name","state","pid","restarts","health","exit_code","started_at","members",'
        '"namespace"}',
    )
    parser.add_argument("services", nargs="*", metavar="SERVICE")
    parser.set_defaults(func=main)
