"""``zendock contract [SERVICE] [--json | --markdown]``: a service's contract, what a replacement must do.

Without SERVICE: the services that have one. The same text as ``docs/contracts/`` (see
:mod:`deploy.contracts.document`), printed from the code that zendock's own services are held to.
"""

from __future__ import annotations

import argparse
import json

from rich.console import Console
from rich.table import Table

from deploy.contracts.document import contract_json, contract_markdown
from shared.config_errors import ConfigError
from shared.contracts import CONTRACTS, Contract


def _table(contract: Contract, console: Console) -> None:
    console.print(f"[bold]{contract.service}[/] (contract {contract.version}): {contract.summary}")
    table = Table(show_header=True, header_style="bold")
    for column in ("kind", "key", "type", "rate (sim)", "frame", "when"):
        table.add_column(column)
    for t in contract.publishes:
        table.add_row(
            "publishes",
            t.name,
            t.type.TYPE_NAME,
            f"{t.rate_hz:g} Hz" if t.rate_hz else "events",
            t.frame_id,
            t.when or "always",
        )
    for t in contract.subscribes:
        table.add_row(
            "subscribes",
            ("*/" if t.fleet_wide else "") + t.name,
            t.type.TYPE_NAME,
            "",
            "",
            t.when or "always",
        )
    for r in contract.serves:
        table.add_row("serves", r.name, r.type.type_name, "", "", r.when or "always")
    for r in contract.calls:
        table.add_row("calls", r.name, r.type.type_name, "", "", r.when or "always")
    for a in contract.serves_actions:
        table.add_row("serves action", a.name, a.type.type_name, "", "", a.when or "always")
    for a in contract.uses_actions:
        table.add_row("uses action", a.name, a.type.type_name, "", "", a.when or "always")
    console.print(table)
    for line in contract.behaviour:
        console.print(f"conform checks: {line}")
    console.print(f"the whole contract: zendock contract {contract.service} --markdown (or docs/contracts/)")


def _run(args: argparse.Namespace) -> int:
    console = Console(highlight=False)
    if args.service is None:
        for each in CONTRACTS.values():
            print(f"{each.service:12s} {each.summary}")
        return 0
    if args.service not in CONTRACTS:
        raise ConfigError(f"no contract for {args.service!r} (one of: {', '.join(CONTRACTS)})")
    contract = CONTRACTS[args.service]
    if args.json:
        print(json.dumps(contract_json(contract), indent=2))
    elif args.markdown:
        print(contract_markdown(contract))
    else:
        _table(contract, console)
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "contract",
        help="what a service must publish, answer and survive (to write a replacement)",
        description="Print a service's contract: its keys, types, rates, requests, actions, what the launcher "
        "hands it and what zendock conform checks. Without SERVICE: the services that have one.",
    )
    parser.add_argument(
        "service", nargs="?", metavar="SERVICE", help="a zendock service (battery, docking, ...)"
    )
    form = parser.add_mutually_exclusive_group()
    form.add_argument(
        "--json", action="store_true", help="the whole contract as JSON, with every type's JSON Schema"
    )
    form.add_argument(
        "--markdown", action="store_true", help="the documentation page (docs/contracts/SERVICE.md)"
    )
    parser.set_defaults(func=_run)
