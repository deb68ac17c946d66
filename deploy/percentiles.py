"""The one percentile every reported figure uses (trials, chaos, benches): the nearest rank, always a
value that was measured, as numpy's ``percentile(method="inverted_cdf")`` computes it (Hyndman and Fan's
definition 1). A median stays the usual one (with an even count, the mean of the two middle values), as
every median zendock has reported was computed.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np


def percentile(values: Iterable[float], q: float) -> float:
    """The nearest-rank ``q`` quantile (0 <= q <= 1) of ``values``; NaN when there are none."""
    if not 0.0 <= q <= 1.0:
        raise ValueError(f"q is a fraction in [0, 1], got {q}")
    data = np.fromiter(values, dtype=float)
    if data.size == 0:
        return math.nan
    return float(np.percentile(data, 100.0 * q, method="inverted_cdf"))


def median(values: Iterable[float]) -> float:
    """The median of ``values`` (the mean of the two middle values for an even count); NaN when there are none."""
    data = np.fromiter(values, dtype=float)
    return float(np.median(data)) if data.size else math.nan
