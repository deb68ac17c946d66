"""``zendock keys hz KEY...``: how often messages arrive, as ``ros2 topic hz`` prints it.

Arrival times are wall-clock receive times, or with ``--sim-time`` the namespace's ``clock`` at receipt
(so the rate is per simulated second, what a node on sim time sees).
"""

from __future__ import annotations

import threading
from typing import TextIO

from deploy.keys.connection import BusOptions
from deploy.keys.monitor import KeyStats, MonitorRequest, run_monitor
from deploy.keys.sampling import ReceivedSample
from deploy.keys.stats import RateSummary, RateWindow


class RateStats(KeyStats):
    needs = "two messages"

    def __init__(self, key: str, window: int) -> None:
        super().__init__(key)
        self._window = RateWindow(window)

    def add(self, sample: ReceivedSample, sim_now_s: float | None) -> None:
        self.count += 1
        self._window.add(sim_now_s if sim_now_s is not None else sample.monotonic_s)

    def summary(self, monotonic_now_s: float) -> RateSummary | None:
        return self._window.summary()


def run_hz(
    options: BusOptions, request: MonitorRequest, out: TextIO, stop: threading.Event | None = None
) -> int:
    return run_monitor("hz", options, request, RateStats, out, stop)
