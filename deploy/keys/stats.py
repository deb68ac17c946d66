"""Sliding-window statistics for ``hz``, ``bw`` and ``delay``, with their ``ros2 topic`` print formats.

Rate follows ``ros2 topic hz`` (ros2topic/verb/hz.py): the window holds the last N inter-arrival
intervals; rate is 1 / mean interval, and min, max and std dev are over the intervals. Bandwidth follows
``ros2 topic bw``: bytes in the window over the time since the window's oldest message. Pure code, no bus.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import asdict, dataclass
from typing import Any

DEFAULT_RATE_WINDOW = 10_000
DEFAULT_BW_WINDOW = 100


@dataclass(frozen=True)
class SpreadStats:
    """mean, min, max and population std dev of a window of values (seconds)."""

    mean: float
    min: float
    max: float
    std_dev: float
    window: int


def spread(values: list[float] | deque[float]) -> SpreadStats | None:
    if not values:
        return None
    n = len(values)
    mean = math.fsum(values) / n
    std = math.sqrt(math.fsum((v - mean) ** 2 for v in values) / n)
    return SpreadStats(mean, min(values), max(values), std, n)


class RateWindow:
    """Arrival times in, rate statistics out."""

    def __init__(self, window: int = DEFAULT_RATE_WINDOW) -> None:
        if window < 1:
            raise ValueError(f"window must be at least 1, got {window}")
        self._intervals: deque[float] = deque(maxlen=window)
        self._last: float | None = None
        self.count = 0

    def add(self, arrival_s: float) -> None:
        """One message arrived at ``arrival_s``; a clock jumping back (sim reset) restarts the intervals."""
        self.count += 1
        if self._last is not None:
            interval = arrival_s - self._last
            if interval < 0:
                self._intervals.clear()
            else:
                self._intervals.append(interval)
        self._last = arrival_s

    def summary(self) -> RateSummary | None:
        """``None`` until two messages have arrived."""
        stats = spread(self._intervals)
        if stats is None:
            return None
        rate = 1.0 / stats.mean if stats.mean > 0 else 0.0
        return RateSummary(rate, stats.min, stats.max, stats.std_dev, stats.window + 1, self.count)


@dataclass(frozen=True)
class RateSummary:
    rate_hz: float
    min_s: float
    max_s: float
    std_dev_s: float
    window: int  # messages in the window
    count: int  # messages received in all

    def text(self) -> str:
        return (
            f"average rate: {self.rate_hz:.3f}\n"
            f"\tmin: {self.min_s:.3f}s max: {self.max_s:.3f}s std dev: {self.std_dev_s:.5f}s window: {self.window}"
        )

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


class DelayWindow:
    """Delays in (receive time minus header stamp), statistics out."""

    def __init__(self, window: int = DEFAULT_RATE_WINDOW) -> None:
        if window < 1:
            raise ValueError(f"window must be at least 1, got {window}")
        self._delays: deque[float] = deque(maxlen=window)
        self.count = 0

    def add(self, delay_s: float) -> None:
        self.count += 1
        self._delays.append(delay_s)

    def summary(self) -> DelaySummary | None:
        stats = spread(self._delays)
        if stats is None:
            return None
        return DelaySummary(stats.mean, stats.min, stats.max, stats.std_dev, stats.window, self.count)


@dataclass(frozen=True)
class DelaySummary:
    average_s: float
    min_s: float
    max_s: float
    std_dev_s: float
    window: int
    count: int

    def text(self) -> str:
        return (
            f"average delay: {self.average_s:.3f}\n"
            f"\tmin: {self.min_s:.3f}s max: {self.max_s:.3f}s std dev: {self.std_dev_s:.5f}s window: {self.window}"
        )

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


class BandwidthWindow:
    """Message sizes and arrival times in, bytes per second out."""

    def __init__(self, window: int = DEFAULT_BW_WINDOW) -> None:
        if window < 1:
            raise ValueError(f"window must be at least 1, got {window}")
        self._arrivals: deque[tuple[float, int]] = deque(maxlen=window)
        self.count = 0

    def add(self, arrival_s: float, size_bytes: int) -> None:
        self.count += 1
        self._arrivals.append((arrival_s, size_bytes))

    def summary(self, now_s: float) -> BandwidthSummary | None:
        """``None`` before the first message; the rate needs time to have passed since the oldest one."""
        if not self._arrivals:
            return None
        sizes = [size for _, size in self._arrivals]
        elapsed = now_s - self._arrivals[0][0]
        total = sum(sizes)
        rate = total / elapsed if elapsed > 0 else 0.0
        return BandwidthSummary(rate, total / len(sizes), min(sizes), max(sizes), len(sizes), self.count)


@dataclass(frozen=True)
class BandwidthSummary:
    bytes_per_s: float
    mean_bytes: float
    min_bytes: int
    max_bytes: int
    window: int
    count: int

    def text(self) -> str:
        return (
            f"{format_bytes(self.bytes_per_s)}/s from {self.window} messages\n"
            f"\tMessage size mean: {format_bytes(self.mean_bytes)} min: {format_bytes(self.min_bytes)} "
            f"max: {format_bytes(self.max_bytes)}"
        )

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def format_bytes(amount: float) -> str:
    """``512 B``, ``1.24 KB``, ``3.50 MB`` (decimal units, as ``ros2 topic bw``)."""
    if amount < 1000:
        return f"{amount:.0f} B" if float(amount).is_integer() else f"{amount:.2f} B"
    if amount < 1_000_000:
        return f"{amount / 1000:.2f} KB"
    return f"{amount / 1_000_000:.2f} MB"
