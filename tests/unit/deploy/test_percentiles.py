"""The one percentile of every reported figure: nearest rank (a measured value), NaN for no values."""

from __future__ import annotations

import math
import random

import pytest

from deploy.percentiles import median, percentile


def _nearest_rank(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, math.ceil(q * len(ordered)) - 1))]


def test_percentile_is_the_nearest_rank_for_every_size_and_level() -> None:
    rng = random.Random(7)
    for n in range(1, 120):
        values = [rng.uniform(-5.0, 5.0) for _ in range(n)]
        for q in (0.0, 0.01, 0.05, 0.25, 0.5, 0.9, 0.95, 0.99, 1.0):
            assert percentile(values, q) == _nearest_rank(values, q), (n, q)


def test_a_median_is_the_usual_one_and_no_values_give_nan() -> None:
    assert median([10.0, 20.0]) == 15.0
    assert median([3.0, 1.0, 2.0]) == 2.0
    assert percentile(iter([1.0, 2.0, 3.0, 4.0]), 0.99) == 4.0
    assert math.isnan(percentile([], 0.95)) and math.isnan(median([]))
    with pytest.raises(ValueError):
        percentile([1.0], 95)
