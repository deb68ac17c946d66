"""Peak resident memory of each service of a running stack, sampled in the background."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable

import psutil


class PeakRssSampler:
    """Polls ``pids()`` (service name -> pid) and keeps each service's highest RSS, children included."""

    def __init__(self, pids: Callable[[], Iterable[tuple[str, int | None]]], period_s: float = 0.5) -> None:
        self._pids = pids
        self._period_s = period_s
        self.peak_mb: dict[str, float] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="rss-sampler", daemon=True)

    def __enter__(self) -> PeakRssSampler:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)

    def sample(self) -> None:
        for name, pid in self._pids():
            if pid is None:
                continue
            try:
                proc = psutil.Process(pid)
                rss = proc.memory_info().rss + sum(c.memory_info().rss for c in proc.children(recursive=True))
            except psutil.Error:
                continue
            mb = rss / 1e6
            if mb > self.peak_mb.get(name, 0.0):
                self.peak_mb[name] = round(mb, 1)

    def _run(self) -> None:
        while not self._stop.wait(self._period_s):
            try:
                self.sample()
            except Exception:  # a stack going down under us: keep what we have
                continue
