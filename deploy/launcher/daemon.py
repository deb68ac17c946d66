"""The ``zendock up -d`` supervisor: ``python -m deploy.launcher.daemon --project-directory DIR -- SERVICE...``.

``up`` plans the launch once (the stack file, its variables, the profiles, ``--service``, the overrides) and
hands the plan to this process as JSON on its standard input (:func:`~deploy.launcher.plan.plan_to_json`), so
the supervisor runs exactly what ``up`` planned, with nothing loaded or parsed a second time. It is started
in its own session with its output in ``.zendock/<project>/daemon.log`` and runs until ``zendock down``,
SIGINT or SIGTERM.
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Sequence
from pathlib import Path

from deploy.launcher.host import SupervisorHost, run_blocking
from deploy.launcher.plan import LaunchPlan, plan_from_json, plan_to_json
from deploy.launcher.runtime import ControlError, RuntimePaths
from shared.config_errors import ConfigError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m deploy.launcher.daemon", description="run the launch plan read from standard input"
    )
    parser.add_argument("--project-directory", required=True, metavar="DIR", help="where .zendock/ lives")
    parser.add_argument("services", nargs="*", metavar="SERVICE", help="the services to start, in order")
    return parser


def launch_argv(project_directory: Path, services: Sequence[str]) -> list[str]:
    """The daemon's command line; its plan goes to its standard input (:func:`plan_to_json`)."""
    return [
        sys.executable,
        "-m",
        "deploy.launcher.daemon",
        "--project-directory",
        str(project_directory),
        "--",
        *services,
    ]


def plan_input(plan: LaunchPlan) -> bytes:
    """What ``up`` writes to the daemon's standard input."""
    return plan_to_json(plan).encode("utf-8")


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        plan = plan_from_json(sys.stdin.read())
    except ValueError as exc:
        print(f"zendock daemon: standard input: {exc}", file=sys.stderr, flush=True)
        return 2
    try:
        unknown = [name for name in args.services if name not in plan.services]
        if unknown:
            raise ConfigError(f"the plan has no service {', '.join(unknown)}")
        paths = RuntimePaths.for_project(Path(args.project_directory), plan.project)
        host = SupervisorHost(plan, list(args.services), paths, mode="daemon")
        return run_blocking(host, announce=lambda text: print(f"zendock daemon: {text}", flush=True))
    except (ConfigError, ControlError) as exc:
        print(f"zendock daemon: {exc}", file=sys.stderr, flush=True)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
