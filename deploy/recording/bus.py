"""The bus flags ``record`` and ``replay`` share with ``zendock keys`` (same names, same environment)."""

from __future__ import annotations

import argparse

from deploy.keys.connection import DEFAULT_CONNECT_TIMEOUT_S, BusOptions, bus_options
from deploy.options import add_connect_option


def add_bus_flags(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("bus")
    add_connect_option(group)
    group.add_argument(
        "--namespace",
        default=None,
        metavar="NS",
        help="robot namespace keys are relative to (env ZENDOCK_NAMESPACE)",
    )
    group.add_argument(
        "--connect-timeout",
        type=float,
        default=DEFAULT_CONNECT_TIMEOUT_S,
        metavar="S",
        help=f"give up reaching the router after S seconds (default {DEFAULT_CONNECT_TIMEOUT_S:g})",
    )


def options_from(args: argparse.Namespace) -> BusOptions:
    """Raises :class:`~deploy.keys.errors.KeysError` for a bad namespace or timeout."""
    return bus_options(args.connect, args.namespace, args.connect_timeout)
