"""The loop shared by ``hz``, ``bw`` and ``delay``: watch keys, print statistics every second, summarise.

Each verb supplies a :class:`KeyStats` per key; the loop feeds it samples (with the simulation time when
asked), prints its text every period (``no new messages`` when nothing arrived since the last print), and
at the end (``--duration`` elapsed, or Ctrl-C) optionally prints one JSON summary for scripts and
benchmarks. A key that produced no statistics is an error (exit 1) naming the key.
"""

from __future__ import annotations

import json
import math
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, TextIO

from deploy.keys.connection import BusOptions, open_bus, resolve_key
from deploy.keys.errors import EXIT_USAGE, KeysError
from deploy.keys.sampling import KeyWatch, ReceivedSample, SimClock

REPORT_PERIOD_S = 1.0


class Summary(Protocol):
    def text(self) -> str: ...

    def as_dict(self) -> dict[str, Any]: ...


class KeyStats(ABC):
    """Statistics of one watched key."""

    #: What ``summary()`` needs to exist, for the error when it does not (e.g. "two messages").
    needs = "a message"

    def __init__(self, key: str) -> None:
        self.key = key
        self.count = 0

    @abstractmethod
    def add(self, sample: ReceivedSample, sim_now_s: float | None) -> None:
        """Account for one sample; raise :class:`KeysError` if the key cannot be measured at all."""

    @abstractmethod
    def summary(self, monotonic_now_s: float) -> Summary | None:
        """The statistics so far, ``None`` while there are not enough samples."""


@dataclass(frozen=True)
class MonitorRequest:
    """The flags the three statistics verbs share."""

    keys: tuple[str, ...]
    window: int
    sim_time: bool = False
    duration_s: float | None = None
    json: bool = False
    period_s: float = REPORT_PERIOD_S

    def check(self) -> None:
        if not self.keys:
            raise KeysError("give at least one key", EXIT_USAGE)
        if self.window < 1:
            raise KeysError(f"--window must be at least 1, got {self.window}", EXIT_USAGE)
        if self.duration_s is not None and not (self.duration_s > 0 and math.isfinite(self.duration_s)):
            raise KeysError(
                f"--duration must be a positive number of seconds, got {self.duration_s:g}", EXIT_USAGE
            )


def run_monitor(
    verb: str,
    options: BusOptions,
    request: MonitorRequest,
    make_stats: Callable[[str, int], KeyStats],
    out: TextIO,
    stop: threading.Event | None = None,
) -> int:
    """Run a statistics verb until ``--duration`` elapses, ``stop`` is set or Ctrl-C; returns the exit code."""
    request.check()
    keys = list(dict.fromkeys(resolve_key(options.namespace, key) for key in request.keys))
    stats = [make_stats(key, request.window) for key in keys]
    stop = stop or threading.Event()
    fatal: list[KeysError] = []
    started = time.monotonic()
    with open_bus(options) as session:
        clock = SimClock(session, options.namespace) if request.sim_time else None

        def on_sample(index: int, sample: ReceivedSample) -> None:
            if fatal:
                return
            sim_now = clock.now() if clock is not None else None
            if clock is not None and sim_now is None:
                return  # no simulation time yet: nothing to measure against
            try:
                stats[index].add(sample, sim_now)
            except KeysError as exc:
                fatal.append(exc)
                stop.set()

        watch = KeyWatch(session, keys, on_sample)
        try:
            _report_until_done(request, stats, watch.lock, stop, out, fatal)
        finally:
            watch.close()
            if clock is not None:
                clock.close()
    if fatal:
        raise fatal[0]
    elapsed = time.monotonic() - started
    now = time.monotonic()
    with watch.lock:
        summaries = [s.summary(now) for s in stats]
    if request.json:
        out.write(json.dumps(_json_summary(verb, request, stats, summaries, elapsed)) + "\n")
        out.flush()
    missing = [s for s, summary in zip(stats, summaries, strict=True) if summary is None]
    if missing:
        if clock is not None and clock.now() is None:
            raise KeysError(
                f"--sim-time: no time on {clock.key} within {elapsed:.1f} s (is a simulator running?)"
            )
        names = ", ".join(f"{s.key} ({s.count} received)" for s in missing)
        raise KeysError(
            f"{verb} needs {missing[0].needs} per key; not enough within {elapsed:.1f} s on: {names}"
        )
    return 0


def _report_until_done(
    request: MonitorRequest,
    stats: list[KeyStats],
    lock: threading.Lock,
    stop: threading.Event,
    out: TextIO,
    fatal: list[KeysError],
) -> None:
    start = time.monotonic()
    deadline = start + request.duration_s if request.duration_s is not None else math.inf
    next_report = start + request.period_s
    printed_counts = [0] * len(stats)
    try:
        while not stop.is_set():
            now = time.monotonic()
            if now >= deadline:
                break
            stop.wait(max(0.0, min(next_report, deadline) - now))
            if time.monotonic() >= next_report:
                next_report += request.period_s
                if not request.json:
                    _print_reports(stats, lock, printed_counts, out)
    except KeyboardInterrupt:
        pass
    if (
        not request.json
        and not fatal
        and any(s.count > printed for s, printed in zip(stats, printed_counts, strict=True))
    ):
        _print_reports(stats, lock, printed_counts, out)


def _print_reports(
    stats: list[KeyStats], lock: threading.Lock, printed_counts: list[int], out: TextIO
) -> None:
    now = time.monotonic()
    lines = []
    with lock:
        for index, key_stats in enumerate(stats):
            if len(stats) > 1:
                lines.append(f"{key_stats.key}:")
            summary = key_stats.summary(now)
            if key_stats.count == printed_counts[index] or summary is None:
                lines.append("no new messages")
            else:
                lines.append(summary.text())
            printed_counts[index] = key_stats.count
    out.write("\n".join(lines) + "\n")
    out.flush()


def _json_summary(
    verb: str,
    request: MonitorRequest,
    stats: list[KeyStats],
    summaries: list[Summary | None],
    elapsed_s: float,
) -> dict[str, Any]:
    per_key: dict[str, Any] = {}
    for key_stats, summary in zip(stats, summaries, strict=True):
        per_key[key_stats.key] = summary.as_dict() if summary is not None else {"count": key_stats.count}
    return {"verb": verb, "duration_s": round(elapsed_s, 3), "sim_time": request.sim_time, "keys": per_key}
