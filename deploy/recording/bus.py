"""The bus flags ``record`` and ``replay`` share with ``zendock keys`` (same names, same environment)."""

from __future__ import annotations

import argparse

from deploy.keys.connection import BusOptions, bus_options
from deploy.options import add_bus_options


def add_bus_flags(parser: argparse.ArgumentParser) -> None:
    add_bus_options(parser.add_argument_group("bus"))


def options_from(args: argparse.Namespace) -> BusOptions:
    """Raises :class:`~deploy.keys.errors.KeysError` for a bad namespace or timeout."""
    return bus_options(args.connect, args.namespace, args.connect_timeout)
