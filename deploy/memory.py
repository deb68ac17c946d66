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
        """One reading of every service: its process and all its descendants, from one look at the process
        table. Asking each service's process for its children read the whole table once per service, twice
        a second: half the CPU of ``zendock fleet``'s own process while six robots ran."""
        roots = [(name, pid) for name, pid in self._pids() if pid is not None]
        if not roots:
            return
        children: dict[int, list[int]] = {}
        for proc in psutil.process_iter(["ppid"]):
            children.setdefault(proc.info["ppid"], []).append(proc.pid)
        for name, pid in roots:
            rss = _tree_rss(pid, children)
            if rss is None:
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


def _tree_rss(root: int, children: dict[int, list[int]]) -> int | None:
    """Resident bytes of ``root`` and its descendants (``children``: pid -> child pids); None once ``root``
    is gone. A descendant that exits while being read is left out."""
    try:
        total = psutil.Process(root).memory_info().rss
    except psutil.Error:
        return None
    pending = list(children.get(root, ()))
    while pending:
        pid = pending.pop()
        pending.extend(children.get(pid, ()))
        try:
            total += psutil.Process(pid).memory_info().rss
        except psutil.Error:
            continue
    return total
