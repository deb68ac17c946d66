"""Argument types the commands share: each rejects a bad value with a message a user can act on.

argparse names a type in its error by the callable's ``__name__`` when it raises ``ValueError``
(``invalid _count value``); these raise :class:`argparse.ArgumentTypeError` instead, which argparse prints
as is after the option's name (``argument --n: must be a whole number of at least 1, got 'abc'``).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import TypeVar

from deploy.replacements import Replacement, check_unique, parse_replacement
from shared.config_errors import ConfigError

T = TypeVar("T")


def positive_number(text: str) -> float:
    """A finite number above zero (a duration, a scale)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text!r}")
    return value


def count(text: str) -> int:
    """A whole number of at least 1 (runs, robots, workers)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number of at least 1, got {text!r}")
    return value


def seed(text: str) -> int:
    """A whole number of at least 0 (a seed; a generated room's name carries it)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be a whole number of at least 0, got {text!r}")
    return value


def real_time_factor(text: str) -> str:
    """The simulator's real-time factor: a positive number, or ``max`` (as fast as it can step)."""
    if text.strip().lower() == "max":
        return "max"
    try:
        positive_number(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"must be a positive number or max, got {text!r}") from None
    return text


def reporting(parse: Callable[[str], T]) -> Callable[[str], T]:
    """An argument type from a parser that raises ``ValueError`` with the message to show (argparse alone
    would say only 'invalid value')."""

    def convert(text: str) -> T:
        try:
            return parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = parse.__name__
    return convert


def service_replacement(text: str) -> Replacement:
    """``NAME=COMMAND`` of ``--service``: zendock's service NAME replaced by COMMAND (:mod:`deploy.replacements`)."""
    try:
        return parse_replacement(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_service_option(parser: argparse.ArgumentParser) -> None:
    """``--service NAME=COMMAND`` (repeatable), as ``up``, ``demo``, ``trials``, ``fleet`` and ``conform`` take it."""
    parser.add_argument(
        "--service",
        action="append",
        default=[],
        type=service_replacement,
        metavar="NAME=COMMAND",
        dest="replacements",
        help="run COMMAND in place of zendock's service NAME, with the flags and environment zendock's own gets "
        "(repeatable; {robot} in COMMAND becomes the robot's namespace)",
    )


def check_replacements(replacements: list[Replacement]) -> tuple[Replacement, ...]:
    """``--service`` options as given, refusing two for one service (a :class:`ConfigError`, one line)."""
    try:
        return tuple(check_unique(replacements))
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
