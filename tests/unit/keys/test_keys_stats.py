"""Rate, delay and bandwidth windows against hand-computed values."""

from __future__ import annotations

import math

import pytest

from deploy.keys.stats import BandwidthWindow, DelayWindow, RateWindow, format_bytes, spread


def test_rate_of_a_regular_stream() -> None:
    window = RateWindow()
    for i in range(21):
        window.add(10.0 + i * 0.05)
    summary = window.summary()
    assert summary is not None
    assert summary.rate_hz == pytest.approx(20.0)
    assert summary.min_s == pytest.approx(0.05) and summary.max_s == pytest.approx(0.05)
    assert summary.std_dev_s == pytest.approx(0.0, abs=1e-12)
    assert (summary.window, summary.count) == (21, 21)


def test_rate_statistics_of_irregular_intervals() -> None:
    window = RateWindow()
    for t in (0.0, 0.1, 0.3, 0.6):  # intervals 0.1, 0.2, 0.3
        window.add(t)
    summary = window.summary()
    assert summary is not None
    assert summary.rate_hz == pytest.approx(5.0)
    assert summary.min_s == pytest.approx(0.1) and summary.max_s == pytest.approx(0.3)
    assert summary.std_dev_s == pytest.approx(math.sqrt(((0.1) ** 2 + 0 + (0.1) ** 2) / 3))
    assert "average rate: 5.000\n\tmin: 0.100s max: 0.300s std dev: 0.08165s window: 4" == summary.text()


def test_rate_window_keeps_the_last_intervals_only() -> None:
    window = RateWindow(window=2)
    for t in (0.0, 1.0, 1.5, 2.0):
        window.add(t)
    summary = window.summary()
    assert summary is not None and summary.rate_hz == pytest.approx(2.0) and summary.window == 3
    assert summary.count == 4


def test_rate_needs_two_messages_and_survives_a_clock_reset() -> None:
    window = RateWindow()
    assert window.summary() is None
    window.add(5.0)
    assert window.summary() is None
    window.add(1.0)  # simulation reset: time went back
    assert window.summary() is None
    window.add(1.5)
    summary = window.summary()
    assert summary is not None and summary.rate_hz == pytest.approx(2.0)


def test_window_must_be_positive() -> None:
    for make in (RateWindow, DelayWindow, BandwidthWindow):
        with pytest.raises(ValueError):
            make(0)


def test_delay_statistics() -> None:
    window = DelayWindow()
    assert window.summary() is None
    for delay in (0.01, 0.03):
        window.add(delay)
    summary = window.summary()
    assert summary is not None
    assert (summary.average_s, summary.min_s, summary.max_s) == pytest.approx((0.02, 0.01, 0.03))
    assert summary.std_dev_s == pytest.approx(0.01)
    assert summary.text().startswith("average delay: 0.020\n\tmin: 0.010s max: 0.030s")


def test_bandwidth_over_the_window() -> None:
    window = BandwidthWindow(window=3)
    assert window.summary(0.0) is None
    for t, size in ((0.0, 100), (1.0, 200), (2.0, 300), (3.0, 400)):
        window.add(t, size)
    summary = window.summary(now_s=4.0)  # window: 200, 300, 400 since t=1
    assert summary is not None
    assert summary.bytes_per_s == pytest.approx(900 / 3.0)
    assert (summary.mean_bytes, summary.min_bytes, summary.max_bytes) == (300, 200, 400)
    assert (summary.window, summary.count) == (3, 4)
    assert summary.text() == "300 B/s from 3 messages\n\tMessage size mean: 300 B min: 200 B max: 400 B"


def test_byte_units_are_decimal() -> None:
    assert [format_bytes(v) for v in (84, 84.5, 1690, 2_500_000)] == ["84 B", "84.50 B", "1.69 KB", "2.50 MB"]


def test_spread_is_population_std_dev() -> None:
    stats = spread([1.0, 3.0])
    assert stats is not None and stats.std_dev == pytest.approx(1.0) and stats.mean == 2.0
    assert spread([]) is None
