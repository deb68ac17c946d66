"""``zendock up``: start a stack in dependency order, in the foreground or detached (``-d``)."""

from __future__ import annotations

import argparse
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

from deploy.arg_types import add_service_option, reporting
from deploy.commands.down import bring_down
from deploy.launcher.api import is_ready
from deploy.launcher.daemon import launch_argv, plan_input
from deploy.launcher.host import SupervisorHost, run_blocking
from deploy.launcher.logs import failure_line, tail
from deploy.launcher.overrides import parse_set
from deploy.launcher.plan import LaunchPlan, plan_launch
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
from deploy.launcher.status import ServiceStatus, failed_dependency
from deploy.options import add_standby_option
from shared.config_errors import ConfigError

DAEMON_START_TIMEOUT_S = 20.0
#: How much of a failed service's log is searched for the line that says why.
FAILURE_LOG_LINES = 200


def add_launch_options(parser: argparse.ArgumentParser) -> None:
    """Launch-time overrides of the stack's settings."""
    parser.add_argument("--namespace", help="override the stack's namespace (e.g. one robot per project)")
    parser.add_argument(
        "--connect", action="append", metavar="ENDPOINT", help="override zenoh.connect (repeatable)"
    )
    parser.add_argument(
        "--working-dir", metavar="DIR", help="where services run (default: the project directory)"
    )
    parser.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        type=reporting(parse_set),
        metavar="SERVICE.PARAM=VALUE",
        help="a parameter of one of zendock's services, over the stack's (repeatable; e.g. docking.auto_dock=false)",
    )
    add_service_option(parser)


def launch_plan(args: argparse.Namespace, stack: Stack) -> LaunchPlan:
    """The launch ``up`` plans once, whether it supervises in the foreground or hands it to the daemon."""
    return plan_launch(
        stack,
        working_dir=args.working_dir or project_dir(args),
        namespace=args.namespace,
        connect=args.connect,
        standby=args.standby,
    )


def run_foreground(args: argparse.Namespace, stack: Stack, services: list[str], paths: RuntimePaths) -> int:
    plan = launch_plan(args, stack)
    printer = Printer(sys.stdout, services)
    host = SupervisorHost(
        plan, services, paths, mode="foreground", on_line=printer.line, exit_when_settled=True
    )

    def announce(text: str) -> None:
        print(f"zendock: {text}", file=sys.stderr, flush=True)

    return run_blocking(host, announce=announce)


def _started(status: ServiceStatus) -> bool:
    return status.starts > 0 or status.phase == "exited"


def _failed(status: ServiceStatus) -> bool:
    return status.phase == "exited" and status.exit_code != 0


def wait_for_stack(
    paths: RuntimePaths,
    services: list[str],
    *,
    healthy: bool,
    timeout_s: float,
    on_settled: Callable[[ServiceStatus], None] | None = None,
) -> tuple[bool, list[ServiceStatus]]:
    """Poll the supervisor until every service started (or is ready, with ``healthy``), or one failed.

    ``on_settled`` is called once per service, as soon as it is started (ready) or has failed, so a user
    sees each service come up as ``docker compose up --wait`` shows it, not all at the end.
    """
    deadline = time.monotonic() + timeout_s
    statuses: list[ServiceStatus] = []
    settled: set[str] = set()
    while time.monotonic() < deadline:
        reply = request(paths, "ps")
        statuses = [ServiceStatus.from_dict(item) for item in reply["services"] if item["name"] in services]
        for status in statuses:
            if status.name not in settled and (
                _failed(status) or (is_ready(status) if healthy else _started(status))
            ):
                settled.add(status.name)
                if on_settled is not None:
                    on_settled(status)
        if any(_failed(s) for s in statuses):
            return False, statuses
        if len(statuses) == len(services) and all(is_ready(s) if healthy else _started(s) for s in statuses):
            return True, statuses
        time.sleep(0.1)
    return False, statuses


def status_word(status: ServiceStatus, *, wait: bool) -> str:
    """What ``up -d`` says of a service: started, healthy, completed, failed: <why>, or its state."""
    if _failed(status):
        return f"failed: {status.detail}"
    if status.phase == "exited":
        return "completed"
    if wait:
        return (
            "healthy"
            if status.health == "healthy"
            else status.state
            if status.health == "none"
            else status.health
        )
    return "started" if status.starts else status.detail or status.state


def status_line(status: ServiceStatus, *, wait: bool, elapsed_s: float | None = None) -> str:
    """``router: healthy (1.2s)``: the service, its word, and the seconds since ``up`` began (when known)."""
    when = f" ({elapsed_s:.1f}s)" if elapsed_s is not None else ""
    return f"{status.name}: {status_word(status, wait=wait)}{when}"


def failure_reason(paths: RuntimePaths, status: ServiceStatus) -> str:
    """``map failed: zendock map save: nope.yaml: cannot read world file ...``: the line of its log that says why."""
    cause = failure_line([line.text for line in tail(paths.logs_dir, status.name, FAILURE_LOG_LINES)])
    return f"{status.name} failed: {cause or status.detail}"


def root_failures(failed: list[ServiceStatus]) -> tuple[list[ServiceStatus], list[ServiceStatus]]:
    """The failures that are causes, and those only waiting on one of them (their detail repeats its cause)."""
    names = {s.name for s in failed}
    waiting = [s for s in failed if failed_dependency(s.detail or "") in names]
    causes = [s for s in failed if s not in waiting]
    return (causes, waiting) if causes else (failed, [])


def not_ready_reason(paths: RuntimePaths, status: ServiceStatus, timeout_s: float) -> str:
    """``docking not healthy after 120s (its last line: ...)``: a service, often a replacement, that runs but
    never declared its node token."""
    lines = [line.text for line in tail(paths.logs_dir, status.name, FAILURE_LOG_LINES)]
    last = failure_line(lines)
    return f"{status.name} not healthy after {timeout_s:g}s ({f'its last line: {last}' if last else 'it printed nothing'})"


def _hand_over(daemon: subprocess.Popen[bytes], plan: bytes) -> None:
    """Write the plan to the daemon's standard input and close it."""
    assert daemon.stdin is not None
    try:
        with daemon.stdin:
            daemon.stdin.write(plan)
    except BrokenPipeError:
        pass  # it exited at once: its exit code and log are reported by start_daemon


def start_daemon(plan: LaunchPlan, services: list[str], paths: RuntimePaths, directory: Path) -> int:
    """Spawn the supervisor in its own session with ``plan`` and wait until it answers; 0, or 1 with its log."""
    paths.state_dir.mkdir(parents=True, exist_ok=True)
    with paths.daemon_log.open("ab") as log:
        daemon = subprocess.Popen(
            launch_argv(directory, services),
            cwd=directory,
            stdin=subprocess.PIPE,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
    # Written from a thread: a daemon that never reads its plan is caught by the start timeout below.
    threading.Thread(
        target=_hand_over, args=(daemon, plan_input(plan)), name="plan-to-daemon", daemon=True
    ).start()
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
    print(
        f"zendock up: the supervisor did not answer within {DAEMON_START_TIMEOUT_S:g}s (see {paths.daemon_log})",
        file=sys.stderr,
    )
    return 1


def run_detached(args: argparse.Namespace, stack: Stack, services: list[str], paths: RuntimePaths) -> int:
    began = time.monotonic()
    if supervisor_info(paths) is not None:
        if args.replacements:  # the running supervisor keeps the stack it started with
            raise ConfigError(
                f"--service: the project {stack.project_name} is already up with its own services; "
                "`zendock down` first"
            )
        request(paths, "start", services=services)
    else:
        code = start_daemon(launch_plan(args, stack), services, paths, project_dir(args))
        if code:
            return code
    printed: set[str] = set()

    def report(status: ServiceStatus) -> None:
        printed.add(status.name)
        print(status_line(status, wait=args.wait, elapsed_s=time.monotonic() - began), flush=True)

    ok, statuses = wait_for_stack(
        paths, services, healthy=args.wait, timeout_s=args.wait_timeout, on_settled=report
    )
    for status in statuses:  # what the others were doing when the wait ended
        if status.name not in printed:
            print(status_line(status, wait=args.wait), flush=True)
    if not ok:
        failed = [s for s in statuses if _failed(s)]
        if failed:
            # A service that cannot start ends the run: nothing is left running (the logs are kept).
            causes, waiting = root_failures(failed)
            reason = "; ".join(failure_reason(paths, s) for s in causes)
            if waiting:
                reason += f" ({', '.join(s.name for s in waiting)} could not start without it)"
            bring_down(paths)
            print(
                f"zendock up: {reason}; the stack is down (`zendock logs` keeps what it printed)",
                file=sys.stderr,
            )
            return 1
        reason = (
            "; ".join(not_ready_reason(paths, s, args.wait_timeout) for s in statuses if not is_ready(s))
            or f"timed out after {args.wait_timeout:g}s"
        )
        print(
            f"zendock up: {reason}; see `zendock ps` and `zendock logs` (the stack stays up: `zendock down`)",
            file=sys.stderr,
        )
        return 1
    return 0


def main(args: argparse.Namespace) -> int:
    stack = load_project_stack(args)
    services = stack.select(args.services, active_profiles(args, stack))
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
    parser.add_argument(
        "-d", "--detach", action="store_true", help="run in the background; return once started"
    )
    parser.add_argument("--wait", action="store_true", help="detach and return once every service is healthy")
    add_standby_option(parser)
    parser.add_argument("--wait-timeout", type=float, default=120.0, metavar="SECONDS", help="(default 120)")
    parser.add_argument("services", nargs="*", metavar="SERVICE", help="only these (and their dependencies)")
    parser.set_defaults(func=main)
