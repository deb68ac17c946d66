"""The stack a fleet run starts: one simulator for the shared room, the fleet service, and each robot's
services written once as an ``x-robots`` template (the same form a hand-written fleet stack file uses)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from deploy.launcher.composition import members_to_compose
from deploy.replacements import Replacement
from shared.controllers import DEFAULT_CONTROLLER, DETECTORS, ControllerName, DetectorName

#: A planner among other robots: slower (two robots close at twice the speed, and each sees the other only
#: where its lidar last put it) and folding its sensors in twice as often.
FLEET_PLANNER_PARAMS = ("-p", "max_linear_vel_mps=0.4", "-p", "costmap_update_rate_hz=10")
#: A fleet's batteries report twice a second, and at once on a change of status (CHARGING): every robot
#: hears every other's battery (the traffic rule's priority, lowest first), and at 10 Hz that was 60 messages
#: a simulated second for each robot to decode, for a charge that moves a few hundredths of a percent between.
FLEET_BATTERY_PARAMS = ("-p", "publish_rate_hz=2")


@dataclass(frozen=True)
class FleetOptions:
    world: Path
    robots: int | None = None
    duration_s: float = 3600.0
    rtf: str = "4"
    seed: int = 0
    detector: DetectorName = "synthetic"
    controller: ControllerName = DEFAULT_CONTROLLER
    #: The battery drains (and charges) this many times faster than the model's real cell, so that an
    #: hour of simulated time holds several charge cycles per robot.
    drain_scale: float = 8.0
    charge_scale: float = 16.0
    #: Charge at which a docked robot undocks and patrols again.
    resume_at: float = 0.8
    runs_dir: Path = Path("runs")
    #: ``--service NAME=COMMAND``: a user's program in place of zendock's service, in every robot's copy.
    replacements: tuple[Replacement, ...] = ()
    #: ``--compose``: each robot's services in one process ("all"), only the light ones ("light"), or not ("").
    compose: str = ""


def fleet_stack(
    options: FleetOptions, endpoint: str, world_file: Path, robots: list[str], state_dir: Path
) -> dict[str, Any]:
    """A stack file (as data) for ``robots`` sharing the room of ``world_file``."""
    world = str(world_file)
    py = ["python", "-m"]
    template: dict[str, Any] = {
        "battery": {
            "command": [
                *py,
                "services.battery",
                "-p",
                "use_sim_time=true",
                "-p",
                f"drain_scale={options.drain_scale}",
                "-p",
                f"charge_scale={options.charge_scale}",
                "-p",
                f"state_file={state_dir}/${{ROBOT}}/battery.json",
                *FLEET_BATTERY_PARAMS,
            ]
        },
        "pose": {"command": [*py, "services.pose", "-p", "use_sim_time=true"]},
        "planner": {
            "command": [
                *py,
                "services.planner",
                "-p",
                "use_sim_time=true",
                "-p",
                f"map_yaml={state_dir}/map.yaml",
                "-p",
                f"glass_memory_file={state_dir}/${{ROBOT}}/glass_memory.npz",
                *FLEET_PLANNER_PARAMS,
            ],
            "depends_on": {
                "router": {"condition": "service_started"},
                "map": {"condition": "service_completed_successfully"},
            },
        },
        "docking": {
            "command": [
                *py,
                "services.docking",
                "-p",
                "use_sim_time=true",
                "-p",
                f"dock_database={world}",
                "-p",
                f"controller={options.controller}",
                "-p",
                "fleet=true",
                "-p",
                f"resume_at={options.resume_at}",
            ]
        },
    }
    if DETECTORS[options.detector].camera:
        template["perception"] = {"command": [*py, "services.perception", "-p", f"dock_database={world}"]}
    for service in template.values():
        service.setdefault("depends_on", {"router": {"condition": "service_started"}})
        service["restart"] = "on-failure"
        service["healthcheck"] = {"liveliness": True, "timeout": "60s"}
    services: dict[str, Any] = {
        "router": {"command": ["zendock", "router", "--listen", endpoint], "restart": "on-failure"},
        "map": {
            "command": ["zendock", "map", "save", "--world", world, "-o", f"{state_dir}/map.yaml"],
            "restart": "no",
        },
        "simulator": {
            "command": [
                *py,
                "services.simulator",
                "--world",
                world,
                "-p",
                f"rtf={options.rtf}",
                "-p",
                f"seed={options.seed}",
                "-p",
                f"detection.source={options.detector}",
            ],
            "depends_on": {"router": {"condition": "service_started"}},
            "healthcheck": {"liveliness": True, "timeout": "60s"},
            "restart": "on-failure",
        },
        "fleet": {
            "command": [*py, "services.fleet", "-p", f"world={world}"],
            "depends_on": {"router": {"condition": "service_started"}},
            "healthcheck": {"liveliness": True, "timeout": "60s"},
            "restart": "on-failure",
        },
    }
    document: dict[str, Any] = {
        "name": "fleet",
        "namespace": "",
        "zenoh": {"connect": [endpoint]},
        "services": services,
        "x-robots": {"robots": list(robots), "services": template},
    }
    grouped = members_to_compose(template, options.compose, {r.name for r in options.replacements})
    if grouped:
        document["x-compose"] = {
            f"robot_{robot}": [f"{name}_{robot}" for name in grouped] for robot in robots
        }
    return document
