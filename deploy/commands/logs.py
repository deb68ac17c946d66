"""``zendock logs [-f] [--tail N] [SERVICE...]``: what services printed, from their log files on disk.

``-f`` keeps printing new lines (rotation included) until Ctrl-C or until the stack goes down. The stack
file is given with ``--file`` here, since ``-f`` means follow (as in ``docker compose logs``).
"""

from __future__ import annotations

import argparse
import sys
import time

from deploy.launcher.logs import Follower, LogLine, merge_by_time, tail
from deploy.launcher.printer import Printer
from deploy.launcher.project import add_project_options, resolve_project
from deploy.launcher.robot_template import service_for
from deploy.launcher.runtime import supervisor_info
from shared.suggestions import no_such

FOLLOW_POLL_S = 0.2


def main(args: argparse.Namespace) -> int:
    name, paths, stack = resolve_project(args)
    logs_dir = paths.logs_dir
    on_disk = sorted(p.name[: -len(".log")] for p in logs_dir.glob("*.log")) if logs_dir.is_dir() else []
    ordered = [s for s in stack.services if s in on_disk] if stack is not None else []
    available = ordered + [s for s in on_disk if s not in ordered]
    known = list(stack.services) if stack is not None else []
    known += [s for s in available if s not in known]
    services = [service_for(s, known) for s in args.services] or available
    unknown = [s for s in services if s not in known]
    if unknown:
        print(f"zendock logs: {no_such('service', unknown, known)}", file=sys.stderr)
        return 2
    missing = [s for s in services if s not in available]
    if missing:
        print(
            f"zendock logs: no logs for {', '.join(missing)} in {logs_dir} (not started yet?)",
            file=sys.stderr,
        )
        return 1
    printer = Printer(sys.stdout, services, colour=False if args.no_color else None)

    def show(line: LogLine) -> None:
        printer.line(
            line.service, f"{line.stamp} {line.text}" if args.timestamps and line.stamp else line.text
        )

    followers = [Follower(logs_dir, s) for s in services] if args.follow else []
    for line in merge_by_time([tail(logs_dir, s, args.tail) for s in services]):
        show(line)
    if not args.follow:
        return 0
    try:
        while True:
            live = supervisor_info(paths) is not None
            for follower in followers:
                for line in follower.poll():
                    show(line)
            if not live:
                return 0
            time.sleep(FOLLOW_POLL_S)
    except KeyboardInterrupt:
        return 0
    finally:
        for follower in followers:
            follower.close()


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("logs", help="show services' output (per-service log files)")
    add_project_options(parser, short_file_flag=False)
    parser.add_argument("-f", "--follow", action="store_true", help="keep printing new lines")
    parser.add_argument("-n", "--tail", type=int, metavar="N", help="only the last N lines of each service")
    parser.add_argument("-t", "--timestamps", action="store_true", help="show each line's UTC time")
    parser.add_argument("--no-color", action="store_true")
    parser.add_argument("services", nargs="*", metavar="SERVICE")
    parser.set_defaults(func=main)
