"""``x-robots``: a fleet's per-robot services written once, expanded per robot with ``${ROBOT}``."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.launcher import load_stack
from deploy.launcher.robot_template import RobotTemplateError, expand_robots, service_for
from shared.config_errors import ConfigError

FLEET_STACK = """
name: fleet
services:
  router:
    command: [zendock, router]
  map:
    command: [zendock, map, save, --world, "${WORLD:-w.yaml}"]
    restart: "no"
x-robots:
  robots: [r1, r2]
  services:
    battery:
      command: [python, -m, services.battery, -p, use_sim_time=true]
      depends_on: {router: {condition: service_started}}
      healthcheck: {liveliness: true, timeout: 20s}
    planner:
      command: [python, -m, services.planner, -p, "glass_memory_file=.zendock/${ROBOT}/glass.npz"]
      depends_on:
        map: {condition: service_completed_successfully}
        battery: {condition: service_started}
"""


def test_each_robot_gets_its_services_in_its_namespace(tmp_path: Path) -> None:
    path = tmp_path / "fleet.yaml"
    path.write_text(FLEET_STACK)
    stack = load_stack(path, env={"WORLD": "deploy/worlds/fleet/warehouse.yaml"}, project_dir=tmp_path)
    assert set(stack.services) == {"router", "map", "battery_r1", "planner_r1", "battery_r2", "planner_r2"}
    planner = stack.services["planner_r2"]
    assert planner.namespace == "r2"
    assert "glass_memory_file=.zendock/r2/glass.npz" in planner.command
    assert set(planner.depends_on) == {"map", "battery_r2"}, "its own robot's battery, the shared map"
    assert set(stack.services["battery_r1"].depends_on) == {"router"}
    assert "deploy/worlds/fleet/warehouse.yaml" in stack.services["map"].command, "${VAR} still interpolated"
    assert stack.services["battery_r2"].healthcheck.liveliness == "battery", "the node, not the expanded name"


def test_robot_slash_service_names_a_robots_copy() -> None:
    services = ["router", "planner_r2", "battery_r2"]
    assert service_for("r2/planner", services) == "planner_r2"
    assert service_for("r3/planner", services) == "r3/planner", "no such robot: left for the error"
    assert service_for("router", services) == "router"


@pytest.mark.parametrize(
    ("block", "message"),
    [
        ("x-robots: [r1]", "expected a mapping"),
        ("x-robots: {robots: [], services: {a: {command: [x]}}}", "non-empty list of robot names"),
        ("x-robots: {robots: [1r], services: {a: {command: [x]}}}", "is not a robot name"),
        ("x-robots: {robots: [r1, r1], services: {a: {command: [x]}}}", "named twice"),
        ("x-robots: {robots: [r1], services: {}}", "service templates"),
        (
            "x-robots: {robots: [r1], services: {router: {command: [x]}}}\nservices: {router_r1: {command: [y]}}",
            "already named 'router_r1'",
        ),
        ("x-robots: {robots: [r1], services: {a: {command: [x], depends_on: 3}}}", "depends_on: expected"),
    ],
)
def test_a_bad_template_is_one_clear_error(tmp_path: Path, block: str, message: str) -> None:
    path = tmp_path / "bad.yaml"
    text = (
        block
        if "services:" in block.split("\n")[-1]
        else f"services: {{router: {{command: [zendock, router]}}}}\n{block}"
    )
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_stack(path, env={}, project_dir=tmp_path)


def test_without_x_robots_nothing_changes() -> None:
    doc = {"services": {"a": {"command": ["x"]}}}
    assert expand_robots(doc) is doc
    with pytest.raises(RobotTemplateError):
        expand_robots({"x-robots": {"robots": ["r1"], "services": {"a": "not a mapping"}}})


def test_the_shipped_fleet_stack_runs_three_robots_sharing_docks(tmp_path: Path) -> None:
    from deploy.paths import REPO_ROOT

    stack = load_stack(REPO_ROOT / "deploy/stack-fleet.yaml", env={}, project_dir=tmp_path)
    for robot in ("r1", "r2", "r3"):
        docking = stack.services[f"docking_{robot}"]
        assert docking.namespace == robot and "fleet=true" in docking.command
        assert stack.services[f"planner_{robot}"].healthcheck.liveliness == "planner"
    assert "fleet" in stack.services and "simulator" in stack.services
