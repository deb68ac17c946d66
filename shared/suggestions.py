""" "Did you mean": the known name closest to a mistyped one, for messages that name a mistake.

One rule for every refusal of a name (a service, a parameter, a profile, a record's field): the closest
known name by :mod:`difflib`'s ratio, at its default cut-off of 0.6, or nothing when none is that close.
"""

from __future__ import annotations

from collections.abc import Iterable


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """`` (did you mean X?)`` with the known name closest to ``name``; empty when none is close."""
    import difflib  # noqa: PLC0415 - only a refused name needs it, not a service's start

    close = difflib.get_close_matches(name, list(known), n=1)
    return f" (did you mean {close[0]}?)" if close else ""


def each_with_a_guess(names: Iterable[str], known: Iterable[str]) -> str:
    """``names`` joined by commas, each followed by its :func:`did_you_mean`."""
    candidates = list(known)
    return ", ".join(f"{name}{did_you_mean(name, candidates)}" for name in names)


__all__ = ["did_you_mean", "each_with_a_guess"]
