"""``zendock bench startup``: the phases of a real service's start, and the imports that cost most."""

from __future__ import annotations

import pytest

from deploy.bench.startup import run_startup_bench, top_imports


def test_a_services_start_splits_into_interpreter_imports_and_the_rest() -> None:
    report = run_startup_bench(repeats=1, services=["battery"])
    row = report["services"]["battery"]
    assert row["interpreter_ms"] > 0 and row["imports_ms"] > 0
    assert row["to_token_max_ms"] >= row["to_token_ms"] > 0
    # The phases add up to the start (imports and the start are timed in different processes, so on a busy
    # machine one sample of the imports may outlast one start: the rest is then negative, never hidden).
    parts = row["interpreter_ms"] + row["imports_ms"] + row["session_and_ready_ms"]
    assert parts == pytest.approx(row["to_token_ms"], abs=0.2)
    assert row["top_imports_ms"] and "services.battery.node" not in row["top_imports_ms"]
    # It says how many of zendock's modules the import compiled for want of a bytecode cache.
    assert row["own_modules"] > 10 and 0 <= row["compiled_from_source"] <= row["own_modules"]
    # From a warm standby the service reaches the bus too (how much sooner is the benchmark's to say).
    assert row["from_standby_max_ms"] >= row["from_standby_ms"] > 0


def test_the_heaviest_imports_are_named_with_their_cumulative_time() -> None:
    heaviest = top_imports("services.pose.node", count=3)
    assert len(heaviest) == 3 and all(ms > 0 for _, ms in heaviest)
    assert [ms for _, ms in heaviest] == sorted((ms for _, ms in heaviest), reverse=True)


def test_an_unknown_service_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match="unknown service.*nowhere"):
        run_startup_bench(repeats=1, services=["nowhere"])
