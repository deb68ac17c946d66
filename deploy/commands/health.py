"""``zendock health NODE...``: exit 0 when every named node's liveliness token is up on the bus.

The container health check: a service in its own container is healthy when the router sees its node's
token, the same test ``zendock up`` makes for a stack file's ``healthcheck: {liveliness: true}``. It asks
the router once (a liveliness query), so it costs one short client session, and prints what is missing.
Exit codes: 0 all alive, 1 some node missing or no router, 2 bad input.
"""

from __future__ import annotations

import argparse
import sys

from deploy.commands.dock import RouterUnreachable, add_connection_flags, client_session, namespace_arg
from shared.names import node_token_key


def alive_nodes(session, namespace: str, nodes: list[str], timeout_s: float) -> set[str]:
    """Which of ``nodes`` have their token up: one liveliness query per node, answered by the router."""
    alive = set()
    for node in nodes:
        key = node_token_key(namespace, node)
        for reply in session.liveliness().get(key, timeout=timeout_s):
            if reply.ok is not None:
                alive.add(node)
    return alive


def health_main(args: argparse.Namespace) -> int:
    namespace = namespace_arg(args)
    try:
        with client_session(args) as session:
            alive = alive_nodes(session, namespace, args.nodes, args.timeout)
    except RouterUnreachable as exc:
        print(f"zendock health: {exc}", file=sys.stderr)
        return 1
    missing = [n for n in args.nodes if n not in alive]
    if missing:
        where = f" in namespace {namespace!r}" if namespace else ""
        print(f"zendock health: no liveliness token from {', '.join(missing)}{where}", file=sys.stderr)
        return 1
    if not args.quiet:
        print(f"alive: {', '.join(args.nodes)}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "health",
        help="exit 0 when the named nodes' liveliness tokens are up (a container health check)",
        description="Exit 0 when every named node's liveliness token is up on the bus.",
    )
    parser.add_argument(
        "nodes", nargs="+", metavar="NODE", help="node name (a service's node is named like it)"
    )
    add_connection_flags(parser)
    parser.add_argument(
        "--timeout",
        type=float,
        default=2.0,
        metavar="S",
        help="wait this long for the router's answer (default 2)",
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing when healthy")
    parser.set_defaults(func=health_main)
