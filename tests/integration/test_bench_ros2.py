"""``zendock bench ros2`` runs end to end: every type crosses the bridge, every figure is finite."""

from __future__ import annotations

import math

from deploy.bench.ros2 import CASES, run_ros2_bench


def test_every_type_crosses_the_bridge_with_finite_figures() -> None:
    report = run_ros2_bench(messages=20, burst_s=0.2)
    assert set(report["cases"]) == {case.topic for case in CASES}
    for topic, row in report["cases"].items():
        assert row["delivered"] >= 18, (topic, row)  # best effort: a sample may drop on a loaded machine
        for key in ("bridge_p50_ms", "bridge_p99_ms", "direct_p50_ms", "bridge_cpu_us_per_message"):
            assert row[key] is not None and math.isfinite(row[key]) and row[key] >= 0, (topic, key, row)
        assert row["burst_forwarded_per_s"] > 0, (topic, row)
