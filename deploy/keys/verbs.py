"""What the bus commands' verbs share (``zendock keys``, ``nodes``, ``param``, ``battery``): the bus flags,
and running a verb with its mistakes said on one line, ``zendock COMMAND VERB: what is wrong``."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from deploy.keys.connection import BusOptions, bus_options
from deploy.keys.errors import KeysError
from deploy.options import add_bus_options

Verb = Callable[[argparse.Namespace, BusOptions], int]


def bus_flags() -> argparse.ArgumentParser:
    """A parent parser with ``--connect``, ``--namespace`` and ``--connect-timeout``."""
    flags = argparse.ArgumentParser(add_help=False)
    add_bus_options(flags.add_argument_group("bus"))
    return flags


def dispatch(command: str, verb_dest: str, verb: Verb) -> Callable[[argparse.Namespace], int]:
    """``verb`` run with the bus options the flags give; a :class:`KeysError` becomes its line and exit code."""

    def run(args: argparse.Namespace) -> int:
        try:
            return verb(args, bus_options(args.connect, args.namespace, args.connect_timeout))
        except KeysError as exc:
            sys.stdout.flush()
            print(f"zendock {command} {getattr(args, verb_dest)}: {exc}", file=sys.stderr)
            return exc.exit_code

    return run
