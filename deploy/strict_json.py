"""JSON that every parser accepts: no NaN or Infinity, ever.

A measure that could not be taken (no trial docked, a lower bound the planner's tool could not compute)
is ``null`` in what zendock prints and writes, with ``<key>_reason`` beside it saying why, instead of
Python's ``NaN``, which ``json.loads`` in other languages (and ``jq``) refuse.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any

#: The reason given for a missing measure when the caller names none.
NOT_MEASURED = "not measured"


def strict(value: Any, reasons: Mapping[str, str] | None = None) -> Any:
    """A copy of ``value`` with every non-finite float replaced by ``None``; in a dict, ``<key>_reason``
    is added beside such a key (from ``reasons``, else :data:`NOT_MEASURED`) unless one is there."""
    reasons = reasons or {}
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        out: dict[str, Any] = {}
        for key, item in value.items():
            out[key] = strict(item, reasons)
            if isinstance(item, float) and not math.isfinite(item) and f"{key}_reason" not in value:
                out[f"{key}_reason"] = reasons.get(key, NOT_MEASURED)
        return out
    if isinstance(value, (list, tuple)):
        return [strict(item, reasons) for item in value]
    return value


def dumps(value: Any, reasons: Mapping[str, str] | None = None, **kwargs: Any) -> str:
    """``json.dumps`` of :func:`strict` ``(value)``; raises ``ValueError`` if a NaN still got through."""
    return json.dumps(strict(value, reasons), allow_nan=False, **kwargs)
