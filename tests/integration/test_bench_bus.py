"""``zendock bench bus`` end to end with a few rounds: both echoes answer, every round is timed on both paths.

The numbers themselves are a benchmark (README), not something a test can hold on a shared machine.
"""

from __future__ import annotations

import math

import psutil
import pytest

from deploy.bench.bus import run_bus_bench


def _live_echo_pids() -> set[int]:
    """Bench echo processes still running (a process that ends while being looked at does not count)."""
    found = set()
    for proc in psutil.process_iter(["cmdline", "status"]):
        if (
            "deploy.bench.echo" in (proc.info["cmdline"] or [])
            and proc.info["status"] != psutil.STATUS_ZOMBIE
        ):
            found.add(proc.pid)
    return found


def test_bus_bench_times_every_round_on_both_paths_and_stops_its_echoes() -> None:
    before = _live_echo_pids()
    result = run_bus_bench(rounds=40)
    report = result.as_dict()
    assert result.rounds == 40
    assert set(report) >= {"rtt_p50_us", "rtt_p99_us", "raw_rtt_p50_us", "ratio"}
    for key in ("rtt_p50_us", "rtt_p99_us", "raw_rtt_p50_us", "raw_rtt_p99_us"):
        assert math.isfinite(report[key]) and report[key] > 0, (key, report)
    assert report["rtt_p99_us"] >= report["rtt_p50_us"]
    assert report["ratio"] == pytest.approx(report["rtt_p50_us"] / report["raw_rtt_p50_us"], rel=0.01)
    leftover = _live_echo_pids() - before
    assert not leftover, f"echo processes left running: {sorted(leftover)}"


def test_bus_bench_refuses_zero_rounds() -> None:
    with pytest.raises(ValueError, match="rounds must be at least 1"):
        run_bus_bench(rounds=0)
