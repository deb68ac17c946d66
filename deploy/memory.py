"""Peak resident memory and CPU time of each service of a running stack, sampled in the background."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable

import psutil


class PeakRssSampler:
    """Polls ``pids()`` (service name -> pid) and keeps each service's highest RSS, children included, and
    the CPU time its processes have used (every process it ran: a restarted service's earlier ones count)."""

    def __init__(self, pids: Callable[[], Iterable[tuple[str, int | None]]], period_s: float = 0.5) -> None:
        self._pids = pids
        self._period_s = period_s
        self.peak_mb: dict[str, float] = {}
        #: The latest CPU seconds (user + system) read of each process, and the service it belongs to.
        self._cpu_s_by_pid: dict[int, tuple[str, float]] = {}
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
            tree = _tree_usage(pid, children)
            if tree is None:
                continue
            rss, cpu_s_by_pid = tree
            mb = rss / 1e6
            if mb > self.peak_mb.get(name, 0.0):
                self.peak_mb[name] = round(mb, 1)
            for process, cpu_s in cpu_s_by_pid.items():
                self._cpu_s_by_pid[process] = (name, cpu_s)

    @property
    def cpu_s(self) -> dict[str, float]:
        """CPU seconds each service has used as of the last sample (at most a sampling period short)."""
        totals: dict[str, float] = {}
        for name, seconds in self._cpu_s_by_pid.values():
            totals[name] = totals.get(name, 0.0) + seconds
        return totals

    def _run(self) -> None:
        while not self._stop.wait(self._period_s):
            try:
                self.sample()
            except Exception:  # a stack going down under us: keep what we have
                continue


def _tree_usage(root: int, children: dict[int, list[int]]) -> tuple[int, dict[int, float]] | None:
    """Resident bytes of ``root`` and its descendants (``children``: pid -> child pids), and each one's CPU
    seconds; None once ``root`` is gone. A descendant that exits while being read is left out."""
    usage: dict[int, float] = {}
    try:
        total = _read(psutil.Process(root), root, usage)
    except psutil.Error:
        return None
    pending = list(children.get(root, ()))
    while pending:
        pid = pending.pop()
        pending.extend(children.get(pid, ()))
        try:
            total += _read(psutil.Process(pid), pid, usage)
        except psutil.Error:
            continue
    return total, usage


def _read(process: psutil.Process, pid: int, usage: dict[int, float]) -> int:
    """One process's resident bytes; its CPU seconds go into ``usage``."""
    with process.oneshot():
        times = process.cpu_times()
        usage[pid] = times.user + times.system
        return int(process.memory_info().rss)
