"""``zendock start|stop|restart|kill SERVICE...``: act on services of a stack that is up."""

from __future__ import annotations

import argparse
import signal
import sys

from deploy.launcher.project import add_project_options, resolve_project
from deploy.launcher.robot_template import service_for
from deploy.launcher.runtime import ControlError, RequestRefused, request
from deploy.launcher.status import ServiceStatus

LIFECYCLE_TIMEOUT_S = 120.0


def _signal_number(text: str) -> int:
    name = text.upper()
    if name.isdigit():
        return int(name)
    try:
        return int(signal.Signals[name if name.startswith("SIG") else f"SIG{name}"])
    except KeyError:
        raise argparse.ArgumentTypeError(f"unknown signal {text!r}") from None


def main(args: argparse.Namespace) -> int:
    name, paths, _ = resolve_project(args)
    fields = {"services": args.services}
    if args.command == "kill":
        fields["signal"] = args.signal
    try:
        reply = request(paths, args.command, timeout_s=LIFECYCLE_TIMEOUT_S, **fields)
    except RequestRefused as exc:  # the stack is up and said why (no such service: ... (services: ...))
        print(f"zendock {args.command}: {exc}", file=sys.stderr)
        return 2
    except ControlError as exc:
        print(f"zendock {args.command}: {exc} (is {name} up? `zendock up -d`)", file=sys.stderr)
        return 1
    statuses = {s["name"]: ServiceStatus.from_dict(s) for s in reply["services"]}
    signalled = set(reply.get("signalled", []))
    for service in args.services or list(statuses):
        status = statuses.get(service_for(service, list(statuses)))
        if status is None:
            continue
        if args.command == "kill":
            print(_kill_line(service, status, status.name in signalled, args.signal))
        else:
            print(f"{service}: {status.state}" + (f" (pid {status.pid})" if status.pid else ""))
    return 0


def _kill_line(service: str, status: ServiceStatus, signalled: bool, signum: int) -> str:
    """What ``kill`` did to one service: the status the reply carries was taken before the process ended."""
    if not signalled:
        return f"{service}: not running ({status.state}), no signal sent"
    try:
        name = signal.Signals(signum).name
    except ValueError:
        name = f"signal {signum}"
    pid = f" pid {status.pid}" if status.pid else ""
    if signum == signal.SIGKILL:
        return f"{service}: killed ({name} to{pid or ' its process group'}; its restart policy applies)"
    return f"{service}: sent {name} to{pid or ' its process group'}"


def register(subparsers: argparse._SubParsersAction) -> None:
    helps = {
        "start": "start services (and the dependencies they need)",
        "stop": "stop services (SIGINT, SIGTERM, SIGKILL within the grace period); all when none given",
        "restart": "stop then start services, re-checking their dependencies",
        "kill": "send a signal to services' process groups (their restart policy applies)",
    }
    for command, text in helps.items():
        parser = subparsers.add_parser(command, help=text, description=text)
        add_project_options(parser)
        if command == "kill":
            parser.add_argument(
                "-s", "--signal", type=_signal_number, default=int(signal.SIGKILL), help="(default KILL)"
            )
        parser.add_argument("services", nargs="+" if command != "stop" else "*", metavar="SERVICE")
        parser.set_defaults(func=main)
