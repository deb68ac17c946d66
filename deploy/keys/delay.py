"""``zendock keys delay KEY...``: receive time minus ``header.stamp``, as ``ros2 topic delay`` prints it.

The receive time is the wall clock, or with ``--sim-time`` the namespace's ``clock``: stamps made on sim
time must be compared with sim time. Payloads that do not decode are skipped (``echo`` shows them); a key
whose messages have no ``header.stamp`` cannot be measured and is an error.
"""

from __future__ import annotations

import threading
from typing import Any, TextIO

from deploy.keys.connection import BusOptions
from deploy.keys.decoding import decode_payload
from deploy.keys.errors import KeysError
from deploy.keys.monitor import KeyStats, MonitorRequest, run_monitor
from deploy.keys.sampling import ReceivedSample
from deploy.keys.stats import DelaySummary, DelayWindow


def header_stamp_s(value: Any) -> float | None:
    """``header.stamp`` of a decoded message in seconds, ``None`` when it has none."""
    if not isinstance(value, dict):
        return None
    header = value.get("header")
    stamp = header.get("stamp") if isinstance(header, dict) else None
    if not isinstance(stamp, dict):
        return None
    sec, nanosec = stamp.get("sec"), stamp.get("nanosec")
    if not isinstance(sec, int) or not isinstance(nanosec, int):
        return None
    return sec + nanosec * 1e-9


class DelayStats(KeyStats):
    def __init__(self, key: str, window: int) -> None:
        super().__init__(key)
        self._window = DelayWindow(window)
        self.skipped = 0

    def add(self, sample: ReceivedSample, sim_now_s: float | None) -> None:
        self.count += 1
        decoded = decode_payload(sample.key, sample.payload, sample.encoding)
        if decoded.undecodable or decoded.invalid:
            self.skipped += 1
            return
        stamp_s = header_stamp_s(decoded.value)
        if stamp_s is None:
            raise KeysError(
                f"{sample.key}: {decoded.type_label} has no header.stamp; delay needs stamped messages"
            )
        now_s = sim_now_s if sim_now_s is not None else sample.wall_s
        self._window.add(now_s - stamp_s)

    def summary(self, monotonic_now_s: float) -> DelaySummary | None:
        return self._window.summary()


def run_delay(
    options: BusOptions, request: MonitorRequest, out: TextIO, stop: threading.Event | None = None
) -> int:
    return run_monitor("delay", options, request, DelayStats, out, stop)
