"""``zendock bench nav2`` measures what it says: one short run with finite figures that add up."""

from __future__ import annotations

import math

import pytest

from deploy.bench.nav2 import ROS2_PYTHON, run_bench

pytestmark = pytest.mark.skipif(
    not ROS2_PYTHON.exists(), reason=".venv-ros2 is missing: `make ros2` builds it"
)


def test_one_short_run_gives_figures_that_add_up() -> None:
    report = run_bench(1, idle_s=1.0, busy_s=2.0)
    (run,) = report["runs"]
    assert all(math.isfinite(value) and value >= 0.0 for value in run.values()), run
    assert run["up_to_active_s"] >= run["healthy_s"] + run["protocol_s"], run
    assert 30.0 < run["face_rss_idle_mb"] < 1000.0, run
    assert report["median"] == run
