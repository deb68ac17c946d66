"""``zendock keys bw KEY...``: bytes per second and message sizes, as ``ros2 topic bw`` prints them.

Sizes are payload bytes as they travel (msgpack), not counting Zenoh's framing.
"""

from __future__ import annotations

import threading
from typing import TextIO

from deploy.keys.connection import BusOptions
from deploy.keys.monitor import KeyStats, MonitorRequest, run_monitor
from deploy.keys.sampling import ReceivedSample
from deploy.keys.stats import BandwidthSummary, BandwidthWindow


class BandwidthStats(KeyStats):
    def __init__(self, key: str, window: int) -> None:
        super().__init__(key)
        self._window = BandwidthWindow(window)

    def add(self, sample: ReceivedSample, sim_now_s: float | None) -> None:
        self.count += 1
        self._window.add(sample.monotonic_s, len(sample.payload))

    def summary(self, monotonic_now_s: float) -> BandwidthSummary | None:
        return self._window.summary(monotonic_now_s)


def run_bw(
    options: BusOptions, request: MonitorRequest, out: TextIO, stop: threading.Event | None = None
) -> int:
    return run_monitor("bw", options, request, BandwidthStats, out, stop)
