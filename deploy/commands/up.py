"""``zendock up``: start a stack in dependency order, in the foreground or detached (``-d``)."""

from __future__ import annotations

import argparse
import subprocess
import sys
import time

from deploy.launcher.api import is_ready
from deploy.launcher.daemon import add_launch_options, launch_argv
from deploy.launcher.host import SupervisorHost, run_blocking
from deploy.launcher.plan import plan_launch
from deploy.launcher.printer import Printer
from deploy.launcher.project import (
    active_profiles,
    add_project_options,
    add_stack_options,
    load_project_stack,
    project_dir,
)
from deploy.launcher.runtime import ControlError, RuntimePaths, request, supervisor_info
from deploy.launcher.stack_file import Stack
from deploy.launcher.status import ServiceStatus

DAEMON_START_TIMEOUT_S = 20.0


def run_foreground(args: argparse.Namespace, stack: Stack, services: list[str], paths: RuntimePaths) -> int:
    plan = plan_launch(stack, working_dir=args.working_dir or project_dir(args), namespace=args.namespace, connect=args.connect)
    printer = Printer(sys.stdout, services)
    host = SupervisorHost(plan, services, paths, mode="foreground", on_line=printer.line, exit_when_settled=True)

    def announce(text: str) -> None:
        print(f"zendock: {text}", file=sys.stderr, flush=True)

    return run_blocking(host, announce=announce)


def _started(status: ServiceStatus) -> bool:
    return status.starts > 0 or status.phase == "exited"


def _failed(status: ServiceStatus) -> bool:
    return status.phase == "exited" and status.exit_code != 0


def wait_for_stack(paths: RuntimePaths, services: list[str], *, healthy: bool, timeout_s: float) -> tuple[bool, list[ServiceStatus]]:
    """Poll the supervisor until every service started (or is ready, with ``healthy``), or one failed."""
    deadline = time.monotonic() + timeout_s
    statuses: list[ServiceStatus] = []
    while time.monotonic() < deadline:
        reply = request(paths, "ps")
        statuses = [ServiceStatus.from_dict(item) for item in reply["services"] if item["name"] in services]
        if any(_failed(s) for s in statuses):
            return False, statuses
        if len(statuses) == len(services) and all(is_ready(s) if healthy else _started(s) for s in statuses):
            return True, statuses
        time.sleep(0.1)
    return False, statuses


def start_daemon(args: argparse.Namespace, services: list[str], paths: RuntimePaths) -> int:
    """Spawn the supervisor in its own session and wait until it answers; 0, or 1 with its log shown."""
    paths.state_dir.mkdir(parents=True, exist_ok=True)
    with paths.daemon_log.open("ab") as log:
        daemon = subprocess.Popen(
            launch_argv(args, services),
            cwd=project_dir(args),
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
    deadline = time.monotonic() + DAEMON_START_TIMEOUT_S
    while time.monotonic() < deadline:
        if daemon.poll() is not None:
            print(f"zendock up: the supervisor exited with code {daemon.returncode}:", file=sys.stderr)
            print(paths.daemon_log.read_text(encoding="utf-8", errors="replace")[-4000:], file=sys.stderr)
            return 1
        if supervisor_info(paths) is not None:
            try:
                request(paths, "info", timeout_s=2.0)
                return 0
            except ControlError:
                pass
        time.sleep(0.05)
    print(f"zendock up: the supervisor did not answer within {DAEMON_START_TIMEOUT_S:g}s (see {paths.daemon_log})", file=sys.stderr)
    return 1


def run_detached(args: argparse.Namespace, stack: Stack, services: list[str], paths: RuntimePaths) -> int:
    if supervisor_info(paths) is not None:
        request(paths, "start", services=services)
    else:
        code = start_daemon(args, services, paths)
        if code:
            return code
    ok, statuses = wait_for_stack(paths, services, healthy=args.wait, timeout_s=args.wait_timeout)
    for status in statuses:
        if _failed(status):
            word = f"failed: {status.detail}"
        elif status.phase == "exited":
            word = "completed"
        elif args.wait:
            word = "healthy" if status.health == "healthy" else status.state if status.health == "none" else status.health
        else:
            word = "started" if status.starts else status.detail or status.state
        print(f"{status.name}: {word}")
    if not ok:
        reason = "a service failed" if any(_failed(s) for s in statuses) else f"timed out after {args.wait_timeout:g}s"
        print(f"zendock up: {reason}; see `zendock ps` and `zendock logs` (the stack stays up: `zendock down`)", file=sys.stderr)
        return 1
    return 0


def main(args: argparse.Namespace) -> int:
    stack = load_project_stack(args)
    services = stack.select(args.services, active_profiles(args))
    paths = RuntimePaths.for_project(project_dir(args), stack.project_name)
    try:
        if args.detach or args.wait:
            return run_detached(args, stack, services, paths)
        return run_foreground(args, stack, services, paths)
    except ControlError as exc:
        print(f"zendock up: {exc}", file=sys.stderr)
        return 1


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "up",
        help="start the stack (foreground, or -d)",
        description="Start the stack's services in dependency order. In the foreground every line is printed "
        "with its service's name; Ctrl-C stops everything (twice: kill at once).",
    )
    add_project_options(parser)
    add_stack_options(parser)
    add_launch_options(parser)
    parser.add_argument("-d", "--detach", action="store_true", help="run in the background; return once started")
    parser.add_argument("--wait", action="store_true", help="detach and return once every service is healthy")
    parser.add_argument("--wait-timeout", type=float, default=120.0, metavar="SECONDS", help="(default 120)")
    parser.add_argument("services", nargs="*", metavar="SERVICE", help="only these (and their dependencies)")
    parser.set_defaults(func=main)
