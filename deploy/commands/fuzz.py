"""``zendock fuzz``: send malformed messages and requests to a running stack, and report what was sent.

A robustness check, not a test: run it against a stack (``zendock up -d --wait``), then look at
``zendock ps`` (still running?) and ``zendock logs`` (rejections logged, rate-limited). Exit codes: 0 the run
finished, 1 no router answered or no zendock service announced itself in the namespace, 2 bad arguments.
"""

from __future__ import annotations

import argparse
import os
import sys

import zenoh

from deploy.fuzz import FuzzOptions, FuzzReport, run_fuzz
from deploy.keys.connection import resolve_endpoints
from deploy.options import add_connect_option
from shared.config_errors import ConfigError
from shared.names import normalise_namespace


def options_from_args(args: argparse.Namespace) -> FuzzOptions:
    raw_namespace = os.environ.get("ZENDOCK_NAMESPACE", "") if args.namespace is None else args.namespace
    try:
        return FuzzOptions(
            connect=resolve_endpoints(args.connect),
            namespace=normalise_namespace(raw_namespace),
            messages=args.messages,
            seed=args.seed,
            rate_hz=args.rate,
            time_limit_s=args.time_limit,
            query_timeout_s=args.query_timeout,
            huge_budget=args.huge_budget,
            zenoh_config=args.zenoh_config,
        )
    except ValueError as exc:
        raise ConfigError(str(exc)) from None


def print_summary(report: FuzzReport) -> None:
    from rich.console import Console  # noqa: PLC0415 - only for the table
    from rich.table import Table  # noqa: PLC0415

    summary = report.as_dict()
    table = Table(
        title=f"zendock fuzz: {summary['sent']} sent in {summary['elapsed_s']:.1f} s "
        f"(seed {report.seed}, stopped by {report.stopped_by})"
    )
    for column in ("key", "kind", "type", "sent", "replies ok/err/none"):
        table.add_column(column, justify="right" if column in ("sent",) else "left")
    for key, entry in summary["keys"].items():
        replies = entry.get("replies")
        table.add_row(
            key if entry["announced"] else f"{key} (not announced)",
            entry["kind"],
            entry["type"] or "?",
            str(entry["sent"]),
            f"{replies['ok']}/{replies['error']}/{replies['none']}" if replies else "",
        )
    console = Console()
    console.print(table)
    console.print(f"payload kinds: {summary['kinds']}")
    if summary["decoder_errors"]:
        console.print(
            f"[bold red]{summary['decoder_errors']} payloads broke a decoder with something other than "
            "a MessageError[/]: see --json, keys.*.decoder_errors"
        )
    if summary["skipped_wildcard_keys"]:
        console.print(f"skipped (wildcard subscriptions): {', '.join(summary['skipped_wildcard_keys'])}")


def main(args: argparse.Namespace) -> int:
    options = options_from_args(args)

    def progress(sent: int, total: int) -> None:
        if not args.json:
            print(f"zendock fuzz: {sent}/{total}", file=sys.stderr, flush=True)

    try:
        report = run_fuzz(options, progress)
    except zenoh.ZError as exc:
        detail = str(exc).split(" at /")[0]
        print(
            f"zendock fuzz: cannot reach a Zenoh router at {', '.join(options.connect)} ({detail})",
            file=sys.stderr,
        )
        return 1
    if args.json:
        print(report.to_json())
    else:
        print_summary(report)
    if report.announced == 0:
        print(
            f"zendock fuzz: no zendock service announced itself in namespace {options.namespace!r}; "
            "is the stack up, and is --namespace right?",
            file=sys.stderr,
        )
        return 1
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "fuzz",
        help="send malformed messages and requests to a running stack",
        description="Send malformed payloads (from each key's schema) to every key and request endpoint "
        "of a running stack on this machine, and report what was sent.",
    )
    add_connect_option(parser)
    parser.add_argument("--namespace", default=None, help="robot namespace (default: ZENDOCK_NAMESPACE)")
    parser.add_argument("--messages", type=int, default=5000, help="how many to send in all (default 5000)")
    parser.add_argument(
        "--seed", type=int, default=0, help="random seed: the same seed sends the same payloads"
    )
    parser.add_argument(
        "--rate", type=float, default=0.0, help="messages per second (default 0: as fast as possible)"
    )
    parser.add_argument(
        "--time-limit",
        type=float,
        default=300.0,
        metavar="S",
        help="stop after S seconds whatever the count (default 300)",
    )
    parser.add_argument(
        "--query-timeout",
        type=float,
        default=1.0,
        metavar="S",
        help="how long a request waits for its reply (default 1)",
    )
    parser.add_argument(
        "--huge-budget",
        type=int,
        default=4,
        metavar="N",
        help="at most N arrays over the size limit, 4 MB each (default 4)",
    )
    parser.add_argument(
        "--zenoh-config",
        metavar="FILE",
        help="Zenoh json5 file applied first, e.g. deploy/zenoh/secure/operator.json5",
    )
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.set_defaults(func=main)
