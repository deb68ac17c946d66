"""The kit's pure modules load without the bus, so algorithm modules built on them stay bus-free."""

from __future__ import annotations

import subprocess
import sys

import pytest

PURE_MODULES = [
    "shared.geometry",
    "shared.frames",
    "shared.world",
    "shared.messages",
    "shared.topics",
    "shared.parameters",
    "shared.ros2.wire",
    "shared.ros2.types",
    "services.ros2_bridge.demand",
    "shared.interface_types",
    "shared.tf_buffer",
    "shared.interfaces.docking",
    "shared.interfaces.navigation",
    "shared.fleet_answer",
    "shared.controllers",
    "shared.models.infrared",
    "shared.models.dock_contact",
    "shared.models.raycast",
]
ALGORITHM_MODULES = [
    "services.docking.executive",
    "services.docking.task_life",
    "services.docking.reporting",
    "services.docking.traffic_policy",
    "services.docking.controllers",
    "services.docking.params",
    "services.docking.graceful",
    "services.docking.docking_run",
    "shared.pose_tracking",
    "services.planner.astar",
    "services.planner.costmap",
    "services.battery.model",
]


@pytest.mark.parametrize("module", PURE_MODULES + ALGORITHM_MODULES)
def test_module_imports_without_zenoh(module: str) -> None:
    probe = f"import sys, {module}; print('zenoh' in sys.modules)"
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=60, check=False
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False", f"importing {module} loads zenoh"
