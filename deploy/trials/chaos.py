"""Fault injection for campaigns: kill robot services at random, measure how fast each comes back."""

from __future__ import annotations

import math
import random
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from deploy.launcher import Launcher
from deploy.percentiles import median, percentile


@dataclass
class ChaosReport:
    kills: int = 0
    recovered: int = 0
    recovery_s: list[float] = field(default_factory=list)
    killed: list[str] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        return {
            "kills": self.kills,
            "recovered": self.recovered,
            **recovery_figures(self.recovery_s),
            "killed": self.killed,
            "recovery_s": [round(t, 3) for t in self.recovery_s],
        }


def recovery_figures(times: list[float]) -> dict[str, float]:
    """Median, p95 and max of the recovery times (NaN when nothing was killed: the report says why)."""
    if not times:
        return {"median_recovery_s": math.nan, "p95_recovery_s": math.nan, "max_recovery_s": math.nan}
    return {
        "median_recovery_s": round(median(times), 2),
        "p95_recovery_s": round(percentile(times, 0.95), 2),
        "max_recovery_s": round(max(times), 2),
    }


class ChaosMonkey:
    """Kills random robot services at random times while trials run; measures how fast each comes back."""

    VICTIMS = ("battery", "pose", "planner", "docking")

    def __init__(self, launcher: Launcher, robots: list[str], period_s: float, seed: int) -> None:
        self._launcher = launcher
        self._names = chaos_victims([(s.name, s.members) for s in launcher.ps()], robots, self.VICTIMS)
        self._period_s = period_s
        self._rng = random.Random(seed + 1)
        self._stop = threading.Event()
        self.report = ChaosReport()
        self._thread = threading.Thread(target=self._run, name="chaos", daemon=True)

    def __enter__(self) -> ChaosMonkey:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=60.0)

    def _run(self) -> None:
        while not self._stop.wait(self._rng.expovariate(1.0 / self._period_s)):
            name = self._rng.choice(self._names)
            try:
                before = self._launcher.status(name).starts
                self._launcher.kill(name)
            except Exception:  # the stack is going down
                return
            killed_at = time.monotonic()
            self.report.kills += 1
            self.report.killed.append(name)
            deadline = killed_at + 60.0
            while time.monotonic() < deadline and not self._stop.is_set():
                status = self._launcher.status(name)
                if status.starts > before and status.health == "healthy":
                    self.report.recovered += 1
                    self.report.recovery_s.append(time.monotonic() - killed_at)
                    break
                time.sleep(0.05)


def chaos_victims(
    services: list[tuple[str, list[str]]], robots: list[str], victims: tuple[str, ...]
) -> list[str]:
    """The processes to kill: each robot's ``<service>_<robot>`` for the victim services, and a composed
    group (``robot_<robot>``: one process) when it runs any of them, so a kill takes its members down together."""
    names = []
    for name, members in services:
        for robot in robots:
            base = name.removesuffix(f"_{robot}")
            if base != name and (base in victims or set(members) & set(victims)):
                names.append(name)
    return names


def combine_chaos(reports: list[dict[str, Any]]) -> dict[str, Any]:
    recovery = [t for report in reports for t in report.get("recovery_s", [])]
    return {
        "kills": sum(r["kills"] for r in reports),
        "recovered": sum(r["recovered"] for r in reports),
        **recovery_figures(recovery),
        "killed": [name for r in reports for name in r.get("killed", [])],
        "recovery_s": recovery,
    }
