"""What zendock prints as JSON parses everywhere: NaN and Infinity become null with a reason."""

from __future__ import annotations

import json
import math

import pytest

from deploy.strict_json import NOT_MEASURED, dumps
from deploy.trials import TrialResult, summarise_results


def _refuse(constant: str) -> None:
    raise ValueError(f"non-standard JSON constant {constant}")


def test_non_finite_numbers_become_null_with_a_reason() -> None:
    text = dumps(
        {"a": math.nan, "b": [1.0, math.inf], "c": {"d": -math.inf}, "e": 2.5},
        reasons={"a": "no docked trial"},
    )
    data = json.loads(text, parse_constant=_refuse)
    assert data == {
        "a": None,
        "a_reason": "no docked trial",
        "b": [1.0, None],
        "c": {"d": None, "d_reason": NOT_MEASURED},
        "e": 2.5,
    }


def test_a_campaign_where_nothing_docked_prints_strict_json() -> None:
    failed = [
        TrialResult(i, "r0", (0.0, 0.0, 0.0), False, False, math.nan, math.nan, math.nan, 0, 0.0)
        for i in range(3)
    ]
    summary = summarise_results(failed, 10.0, "graceful", "room")
    assert math.isnan(summary.median_dock_time_s)
    data = json.loads(dumps(summary.headline()), parse_constant=_refuse)
    assert data["median_dock_time_s"] is None and data["median_dock_time_s_reason"]
    with pytest.raises(ValueError):
        json.loads(json.dumps(summary.headline()), parse_constant=_refuse)  # what plain json.dumps gave
