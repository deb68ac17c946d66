"""Argument types the commands share: each rejects a bad value with a message a user can act on.

argparse names a type in its error by the callable's ``__name__`` when it raises ``ValueError``
(``invalid _count value``); these raise :class:`argparse.ArgumentTypeError` instead, which argparse prints
as is after the option's name (``argument --n: must be a whole number of at least 1, got 'abc'``).
"""

from __future__ import annotations

import argparse
import math


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


def real_time_factor(text: str) -> str:
    """The simulator's real-time factor: a positive number, or ``max`` (as fast as it can step)."""
    if text.strip().lower() == "max":
        return "max"
    try:
        positive_number(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"must be a positive number or max, got {text!r}") from None
    return text
