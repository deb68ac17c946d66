"""The observer's record of one run: what the demo's picture and report take from it."""

from __future__ import annotations

import pytest

from deploy.observer import RunRecord


def _driven(*points: tuple[float, float]) -> list[tuple[float, float, float, float]]:
    return [(0.05 * i, x, y, 0.0) for i, (x, y) in enumerate(points)]


def test_the_pictures_track_starts_where_the_robot_was_put_down() -> None:
    record = RunRecord(driven=_driven((0.0, 0.0), (0.0, 0.0), (2.0, 1.0), (2.02, 1.0), (2.04, 1.01)))
    assert record.driven_since_placed() == [(2.0, 1.0), (2.02, 1.0), (2.04, 1.01)]


def test_a_track_never_put_down_is_kept_whole_even_with_lost_samples() -> None:
    # 0.2 m between samples: eight lost samples at full speed, still a drive
    record = RunRecord(driven=_driven((0.0, 0.0), (0.025, 0.0), (0.225, 0.0), (0.25, 0.0)))
    assert record.driven_since_placed() == [(0.0, 0.0), (0.025, 0.0), (0.225, 0.0), (0.25, 0.0)]
    assert record.driven_length_m() == pytest.approx(0.25)
    assert RunRecord().driven_since_placed() == []
