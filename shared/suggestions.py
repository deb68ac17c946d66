""" "Did you mean": the known name closest to a mistyped one, for messages that name a mistake.

One rule for every refusal of a name (a service, a parameter, a profile, a record's field): the closest
known name by :mod:`difflib`'s ratio, at its default cut-off of 0.6, or nothing when none is that close.
"""

from __future__ import annotations

from collections.abc import Iterable


def closest_names(name: str, known: Iterable[str], n: int = 1, cutoff: float = 0.6) -> list[str]:
    """Up to ``n`` known names closest to ``name``, closest first, none below ``cutoff``."""
    import difflib  # noqa: PLC0415 - only a refused name needs it, not a service's start

    return difflib.get_close_matches(name, list(known), n=n, cutoff=cutoff)


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """`` (did you mean X?)`` with the known name closest to ``name``; empty when none is close."""
    close = closest_names(name, known)
    return f" (did you mean {close[0]}?)" if close else ""


def each_with_a_guess(names: Iterable[str], known: Iterable[str]) -> str:
    """``names`` joined by commas, each followed by its :func:`did_you_mean`."""
    candidates = list(known)
    return ", ".join(f"{name}{did_you_mean(name, candidates)}" for name in names)


def no_such(what: str, unknown: Iterable[str], known: Iterable[str]) -> str:
    """``no such service: plnner (did you mean planner?) (services: a, b)``: the names refused, each with
    its guess, and the names there are (left out when there are none)."""
    candidates = list(known)
    listed = f" ({what}s: {', '.join(candidates)})" if candidates else ""
    return f"no such {what}: {each_with_a_guess(unknown, candidates)}{listed}"


__all__ = ["closest_names", "did_you_mean", "each_with_a_guess", "no_such"]
