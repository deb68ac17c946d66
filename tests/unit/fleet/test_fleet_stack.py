"""The stack a fleet run starts: with ``--compose``, each robot's services in one process."""

from __future__ import annotations

from pathlib import Path

from deploy.fleet.stack import FleetOptions, fleet_stack
from deploy.launcher.stack_file import Stack
from deploy.paths import REPO_ROOT
from deploy.replacements import Replacement

WORLD = REPO_ROOT / "deploy" / "worlds" / "fleet" / "warehouse.yaml"


def _stack(tmp_path: Path, **options: object) -> Stack:
    fleet_options = FleetOptions(world=WORLD, **options)  # type: ignore[arg-type]
    return fleet_stack(fleet_options, "tcp/127.0.0.1:1", WORLD, ["r1", "r2"], tmp_path / "state")


def test_by_default_every_robot_service_is_its_own_process(tmp_path: Path) -> None:
    services = _stack(tmp_path).services
    for robot in ("r1", "r2"):
        assert {f"{name}_{robot}" for name in ("battery", "pose", "planner", "docking")} <= set(services)
    assert not any(name.startswith("robot_") for name in services)


def test_compose_runs_each_robots_services_in_one_container(tmp_path: Path) -> None:
    services = _stack(tmp_path, compose="all").services
    assert not any(name.startswith(("battery_", "pose_", "planner_", "docking_")) for name in services)
    for robot in ("r1", "r2"):
        group = services[f"robot_{robot}"]
        command = list(group.command)
        assert command[:2] == ["zendock", "container"]
        assert group.members == ("battery", "pose", "planner", "docking")
        assert f"glass_memory_file={tmp_path / 'state'}/{robot}/glass_memory.npz" in command, (
            "each robot's own memory"
        )
        assert group.namespace == robot
        # healthy once its last member's node (``docking`` in the robot's namespace) is alive
        assert group.healthcheck is not None and group.healthcheck.liveliness == "docking"
        assert "map" in group.depends_on, "the planner inside waits for the map"


def test_compose_light_groups_battery_and_pose_only(tmp_path: Path) -> None:
    services = _stack(tmp_path, compose="light").services
    command = list(services["robot_r1"].command)
    assert command[2] == "battery" and command.count("+") == 1 and "pose" in command
    assert {"planner_r1", "docking_r1"} <= set(services)
    assert services["robot_r1"].healthcheck.liveliness == "pose"  # type: ignore[union-attr]


def test_a_replaced_service_keeps_its_own_process_beside_the_group(tmp_path: Path) -> None:
    replaced = (Replacement.of("planner", "my-planner --robot {robot}"),)
    services = _stack(tmp_path, compose="all", replacements=replaced).services
    assert list(services["planner_r1"].command)[:3] == ["my-planner", "--robot", "r1"]
    assert "planner" not in list(services["robot_r1"].command)
