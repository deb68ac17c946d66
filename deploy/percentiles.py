"""The one percentile every reported figure uses (trials, chaos, benches): the nearest rank, always a
value that was measured, as numpy's ``percentile(method="inverted_cdf")`` computes it (Hyndman and Fan's
definition 1). A median is the 50th percentile by the same rule: with an even count, the lower of the two
middle values, never their mean.
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
    """``percentile(values, 0.5)``: a measured value; NaN when there are none."""
    return percentile(values, 0.5)
