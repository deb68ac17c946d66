"""``zendock nodes [list | info NODE] [--json]``: the nodes on the bus and their endpoints, like ``ros2 node``.

Exit codes: 0 done, 1 no router or no such node, 2 bad input. See :mod:`deploy.nodes`.
"""

from __future__ import annotations

import argparse
import sys

from deploy.keys.connection import bus_options
from deploy.keys.errors import KeysError
from deploy.keys.verbs import bus_flags
from deploy.nodes import run_nodes


def _run(args: argparse.Namespace) -> int:
    verb = args.nodes_verb or "list"
    try:
        options = bus_options(args.connect, args.namespace, args.connect_timeout)
        return run_nodes(options, getattr(args, "node", None), args.json, sys.stdout)
    except KeysError as exc:
        sys.stdout.flush()
        print(f"zendock nodes {verb}: {exc}", file=sys.stderr)
        return exc.exit_code


def _flags(given_after_verb: bool) -> argparse.ArgumentParser:
    """The bus flags and ``--json``. After the verb their defaults are suppressed, so that the verb's
    parser does not reset what was given before it (``nodes --json list``)."""
    flags = bus_flags()
    flags.add_argument("--json", action="store_true", help="print JSON (for scripts)")
    if given_after_verb:
        for action in flags._actions:
            action.default = argparse.SUPPRESS
    return flags


def register(subparsers: argparse._SubParsersAction) -> None:
    nodes = subparsers.add_parser(
        "nodes",
        parents=[_flags(False)],
        help="nodes on the bus and their endpoints (like ros2 node)",
        description="Nodes on the bus, from the liveliness tokens their endpoints declare (as keys list reads "
        "them). Without a verb: list.",
    )
    verbs = nodes.add_subparsers(dest="nodes_verb", metavar="VERB")
    p = verbs.add_parser(
        "list",
        parents=[_flags(True)],
        help="the nodes (/<ns>/<name>)",
        description="The nodes up, one per line; --namespace limits the list.",
    )
    p.set_defaults(func=_run)
    p = verbs.add_parser(
        "info",
        parents=[_flags(True)],
        help="a node's publishers, subscriptions, services, actions",
        description="A node's publishers, subscriptions, services and actions, with their keys "
        "and types. NODE is /<ns>/<name> as nodes list prints it, or a name in "
        "--namespace.",
    )
    p.add_argument("node", metavar="NODE")
    p.set_defaults(func=_run)
    nodes.set_defaults(func=_run)
