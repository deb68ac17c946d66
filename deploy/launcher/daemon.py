"""The ``zendock up -d`` supervisor: ``python -m deploy.launcher.daemon [options] [SERVICE...]``.

It is started in its own session with its output in ``.zendock/<project>/daemon.log``, loads the stack the
way ``up`` did (same environment, same options), and runs until ``zendock down``, SIGINT or SIGTERM.
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Sequence

from deploy.arg_types import add_service_option
from deploy.launcher.host import SupervisorHost, run_blocking
from deploy.launcher.plan import plan_launch
from deploy.launcher.project import (
    active_profiles,
    add_project_options,
    add_stack_options,
    load_project_stack,
    project_dir,
)
from deploy.launcher.runtime import ControlError, RuntimePaths
from shared.config_errors import ConfigError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m deploy.launcher.daemon")
    add_project_options(parser)
    add_stack_options(parser)
    add_launch_options(parser)
    parser.add_argument("services", nargs="*", metavar="SERVICE")
    return parser


def add_launch_options(parser: argparse.ArgumentParser) -> None:
    """Launch-time overrides of the stack's settings (shared by ``up`` and the daemon)."""
    parser.add_argument("--namespace", help="override the stack's namespace (e.g. one robot per project)")
    parser.add_argument(
        "--connect", action="append", metavar="ENDPOINT", help="override zenoh.connect (repeatable)"
    )
    parser.add_argument(
        "--working-dir", metavar="DIR", help="where services run (default: the project directory)"
    )
    add_service_option(parser)


def launch_argv(args: argparse.Namespace, services: Sequence[str]) -> list[str]:
    """The daemon's command line for an ``up`` invocation's options."""
    argv = [sys.executable, "-m", "deploy.launcher.daemon", "--project-directory", str(project_dir(args))]
    if args.file:
        argv += ["--file", str(args.file)]
    if args.project_name:
        argv += ["--project-name", args.project_name]
    if args.env_file:
        argv += ["--env-file", args.env_file]
    for profile in active_profiles(args):
        argv += ["--profile", profile]
    if args.namespace is not None:
        argv += ["--namespace", args.namespace]
    for endpoint in args.connect or []:
        argv += ["--connect", endpoint]
    if args.working_dir:
        argv += ["--working-dir", args.working_dir]
    for replacement in args.replacements:
        argv += ["--service", f"{replacement.name}={replacement.command}"]
    return [*argv, "--", *services]


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        stack = load_project_stack(args)
        paths = RuntimePaths.for_project(project_dir(args), stack.project_name)
        services = stack.select(args.services, active_profiles(args))
        plan = plan_launch(
            stack,
            working_dir=args.working_dir or project_dir(args),
            namespace=args.namespace,
            connect=args.connect,
        )
        host = SupervisorHost(plan, services, paths, mode="daemon")
        return run_blocking(host, announce=lambda text: print(f"zendock daemon: {text}", flush=True))
    except (ConfigError, ControlError) as exc:
        print(f"zendock daemon: {exc}", file=sys.stderr, flush=True)
        return 2


if __name__ == "__main__":
    sys.exit(main())
