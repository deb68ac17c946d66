"""Durations as people write them in stack files: ``5s``, ``500ms``, ``1m30s``, ``1.5s`` (or plain seconds)."""

from __future__ import annotations

import re

_UNIT_S = {"h": 3600.0, "m": 60.0, "s": 1.0, "ms": 1e-3, "us": 1e-6}
_PART_RE = re.compile(r"(\d+(?:\.\d+)?)(h|ms|us|m|s)")


def parse_duration(value: object) -> float:
    """Seconds from ``"1m30s"``-style text or a non-negative number; ``ValueError`` names what is wrong."""
    if isinstance(value, bool):
        raise ValueError(f"expected a duration like 5s or 500ms, got {value!r}")
    if isinstance(value, (int, float)):
        seconds = float(value)
    elif isinstance(value, str):
        text = value.strip()
        position, seconds = 0, 0.0
        for match in _PART_RE.finditer(text):
            if match.start() != position:
                break
            seconds += float(match.group(1)) * _UNIT_S[match.group(2)]
            position = match.end()
        if not text or position != len(text):
            raise ValueError(f"expected a duration like 5s, 500ms or 1m30s, got {value!r}")
    else:
        raise ValueError(f"expected a duration like 5s or 500ms, got {value!r}")
    if seconds < 0:
        raise ValueError(f"a duration cannot be negative, got {value!r}")
    return seconds


def format_duration(seconds: float) -> str:
    """The shortest text :func:`parse_duration` reads back as ``seconds`` (to the millisecond)."""
    millis = round(seconds * 1000)
    if millis == 0:
        return "0s"
    if millis % 1000:
        return f"{millis}ms" if millis < 1000 else f"{millis / 1000:g}s"
    whole_s = millis // 1000
    minutes, secs = divmod(whole_s, 60)
    if not minutes:
        return f"{secs}s"
    return f"{minutes}m{secs}s" if secs else f"{minutes}m"
