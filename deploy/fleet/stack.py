"""The stack a fleet run starts: one simulator for the shared room, the fleet service, and each robot's
own services in its namespace (a :class:`~deploy.scenario.Scenario` with ``fleet=True``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from deploy.launcher.stack_file import Stack
from deploy.replacements import Replacement
from deploy.scenario import Scenario, scenario_stack
from shared.controllers import DEFAULT_CONTROLLER, ControllerName, DetectorName

#: A planner among other robots: slower (two robots close at twice the speed, and each sees the other only
#: where its lidar last put it) and folding its sensors in twice as often.
FLEET_PLANNER_PARAMS = {"max_linear_vel_mps": 0.4, "costmap_update_rate_hz": 10}
#: A fleet's batteries report twice a second, and at once on a change of status (CHARGING): every robot
#: hears every other's battery (the traffic rule's priority, lowest first), and a fast rate costs every robot
#: decoding for a charge that barely moves between (measurement 75).
FLEET_BATTERY_PARAMS = {"publish_rate_hz": 2}


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
) -> Stack:
    """``robots`` sharing the room of ``world_file``, with the fleet service handing out docks."""
    return scenario_stack(
        Scenario(
            project="fleet",
            world=world_file,
            robots=tuple(robots),
            endpoint=endpoint,
            rtf=options.rtf,
            seed=options.seed,
            controller=options.controller,
            detector=options.detector,
            state_dir=state_dir,
            map_file=f"{state_dir}/map.yaml",
            fleet=True,
            robot_params={
                "battery": {
                    "drain_scale": options.drain_scale,
                    "charge_scale": options.charge_scale,
                    **FLEET_BATTERY_PARAMS,
                },
                "planner": FLEET_PLANNER_PARAMS,
                "docking": {"fleet": True, "resume_at": options.resume_at},
            },
            health_timeout_s=60.0,
            compose=options.compose,
            replacements=options.replacements,
        )
    )
