"""``zendock conform SERVICE [-- COMMAND ...]``: check a program against SERVICE's contract.

Runs the rest of a stack on a private loopback router with COMMAND in place of SERVICE (default:
zendock's own), then the named checks of :mod:`deploy.contracts.conform`. Prints a table (check, result,
evidence), or ``--json``; exit 0 only when every check passes. ``--all`` checks every zendock service
against its own contract, one stack each.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console
from rich.table import Table

from deploy import strict_json
from deploy.arg_types import real_time_factor
from deploy.world_names import world_file_argument
from shared.config_errors import ConfigError
from shared.contracts import CONTRACTS

RESULT_STYLE = {"pass": "[green]{}[/]", "FAIL": "[red]{}[/]", "not run": "[yellow]{}[/]"}


def _table(report, console: Console) -> None:
    verdict = (
        "[green]conforms[/]"
        if report.passed
        else f"[red]does not conform[/] ({len(report.failed())} failed, {len(report.not_run())} not run)"
    )
    table = Table(
        title=f"zendock conform {report.service} (contract {report.contract_version}): {verdict} "
        f"in {report.wall_s:.0f} s"
    )
    table.add_column("check")
    table.add_column("result")
    table.add_column("evidence", overflow="fold")
    for check in report.checks:
        table.add_row(check.name, RESULT_STYLE[check.result].format(check.result), check.evidence)
    console.print(table)
    console.print(f"command: {' '.join(report.command)}\nits output: {report.log}", highlight=False)


def _run(args: argparse.Namespace) -> int:
    from deploy.contracts.conform import ConformOptions, run_conform  # noqa: PLC0415 - heavy imports only when used

    if args.all == bool(args.service):
        raise ConfigError("name one SERVICE (and its COMMAND after --), or give --all")
    if args.all and args.command_words:
        raise ConfigError("--all checks zendock's own services: give no COMMAND")
    world = Path(args.world)
    services = list(CONTRACTS) if args.all else [args.service]
    if args.service and args.service not in CONTRACTS:
        raise ConfigError(f"no contract for {args.service!r} (one of: {', '.join(CONTRACTS)})")
    console = Console(stderr=args.json)
    progress = Console(stderr=True, highlight=False)
    options = ConformOptions(
        world=world, rtf=args.rtf, runs_dir=Path(args.runs_dir) if args.runs_dir else None
    )
    reports = []
    for service in services:
        report = run_conform(
            service,
            args.command_words or None,
            options,
            log=lambda text: progress.print(f"[dim]conform:[/] {text}"),
        )
        _table(report, console)
        reports.append(report)
    if args.json:
        body = reports[0].as_dict() if len(reports) == 1 else {"services": [r.as_dict() for r in reports]}
        print(strict_json.dumps(body))
    return 0 if all(r.passed for r in reports) else 1


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "conform",
        help="check a program against a service's contract (a replacement, or zendock's own)",
        description="Run the rest of a stack on a private router with COMMAND in place of SERVICE and check its "
        "contract: token, endpoints, rates, behaviour, bad requests, malformed payloads, SIGTERM, restart. "
        "Example: zendock conform battery -- python my_battery.py",
    )
    parser.add_argument("service", nargs="?", metavar="SERVICE", help=f"one of: {', '.join(CONTRACTS)}")
    parser.add_argument("--all", action="store_true", help="every zendock service against its own contract")
    parser.add_argument(
        "--world",
        type=world_file_argument,
        default="deploy/worlds/seed_room.yaml",
        help="world file (needs a dock)",
    )
    parser.add_argument("--rtf", type=real_time_factor, default="4", help="the simulator's real-time factor")
    parser.add_argument(
        "--runs-dir", metavar="DIR", help="where each run's directory goes (default: the temp dir)"
    )
    parser.add_argument("--json", action="store_true", help="print the report as JSON on the last line")
    parser.add_argument(
        "command_words",
        nargs="*",
        metavar="-- COMMAND",
        help="the program and its arguments, after -- (default: zendock's own service)",
    )
    parser.set_defaults(func=_run, takes_command=True)
