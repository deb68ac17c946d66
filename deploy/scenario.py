"""A scenario, and the stack that runs it: one room, its robots, how they dock and what stands in for what.

Campaigns (``zendock trials``) and fleets (``zendock fleet``) describe what they want as a :class:`Scenario`;
:func:`scenario_stack` builds the typed stack from it: the router, the map step, one simulator for every
robot, the fleet service when robots share docks, and each robot's own services in its namespace, then the
robot's composition (``--compose``) and the replacements (``--service``) as transformations of that stack.
Nothing is written to disk and read back; the runners keep ``stack.to_dict()`` in their run directories as
the record of what ran.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path

from deploy.launcher.composition import compose_groups, members_to_compose
from deploy.launcher.launch import (
    Dependency,
    ModuleRun,
    ProgramRun,
    ServiceLaunch,
    after,
    liveliness,
    param_flags,
)
from deploy.launcher.restart import RestartPolicy
from deploy.launcher.stack_file import Stack, check_stack
from deploy.replacements import Replacement, apply_replacements
from shared.controllers import DEFAULT_CONTROLLER, DETECTORS, ControllerName, DetectorName

ON_FAILURE = RestartPolicy("on-failure")
#: A robot's services in one process come up one after the other: the group has longer to be healthy.
GROUP_HEALTH_TIMEOUT_S = 60.0
#: Each robot's planner keeps its glass memory in ``<state_dir>/<robot>/`` under this name.
GLASS_MEMORY_FILE = "glass_memory.npz"
#: The order of a robot's services (and of its group's members: the group is healthy with the last).
ROBOT_SERVICES = ("battery", "pose", "planner", "perception", "docking")

Params = Mapping[str, object]


@dataclass(frozen=True)
class Scenario:
    """What a run wants; :func:`scenario_stack` turns it into the services that run it."""

    #: ``trials`` or ``fleet``: the stack's project name.
    project: str
    world: Path
    robots: tuple[str, ...]
    #: The private router's endpoint, where every service connects.
    endpoint: str
    rtf: str = "4"
    seed: int = 0
    controller: ControllerName = DEFAULT_CONTROLLER
    detector: DetectorName = "synthetic"
    #: Where the robots' planners keep glass memories and batteries their charge (``None``: not kept).
    state_dir: Path | None = None
    #: The map step's output, the planners' map.
    map_file: str = ".zendock/maps/map.yaml"
    #: The simulator serves the robots it is told (each alone in its copy of the room); ``False``: the
    #: world's own fleet, sharing one room, with the fleet service beside it.
    fleet: bool = False
    #: The simulator's own parameters beyond rtf, seed and the detection source.
    simulator_params: Params = field(default_factory=dict)
    #: Each robot service's parameters beyond ``use_sim_time`` and what the scenario sets itself.
    robot_params: Mapping[str, Params] = field(default_factory=dict)
    #: How long a service has to declare its liveliness token.
    health_timeout_s: float = 30.0
    #: ``--compose``: each robot's services in one process ("all"), the light ones ("light"), or not ("").
    compose: str = ""
    replacements: tuple[Replacement, ...] = ()


def scenario_stack(scenario: Scenario) -> Stack:
    """The typed stack of ``scenario``, checked, composed and with its replacements applied."""
    world = str(scenario.world)
    started = after(router="service_started")
    services: dict[str, ServiceLaunch] = {
        "router": ServiceLaunch(
            ProgramRun(("zendock", "router", "--listen", scenario.endpoint)), restart=ON_FAILURE
        ),
        "map": ServiceLaunch(
            ProgramRun(("zendock", "map", "save", "--world", world, "-o", scenario.map_file))
        ),
        "simulator": _service(
            scenario,
            "simulator",
            {
                "rtf": scenario.rtf,
                "seed": scenario.seed,
                **({} if scenario.fleet else {"robots": scenario.robots}),
                **scenario.simulator_params,
                "detection.source": scenario.detector,
            },
            leading=("--world", world),
            depends_on=started,
        ),
    }
    if scenario.fleet:
        services["fleet"] = _service(scenario, "fleet", {"world": world}, depends_on=started)
    groups: dict[str, list[str]] = {}
    replaced = {r.name for r in scenario.replacements}
    for robot in scenario.robots:
        members = _robot_services(scenario, robot)
        for name, params in members.items():
            services[f"{name}_{robot}"] = _service(
                scenario,
                name,
                params,
                depends_on=after(router="service_started", map="service_completed_successfully")
                if name == "planner"
                else started,
                namespace=robot,
            )
        grouped = members_to_compose(members, scenario.compose, replaced)
        if grouped:
            groups[f"robot_{robot}"] = [f"{name}_{robot}" for name in grouped]
    services = compose_groups(services, groups)
    for group in groups:
        check = services[group].healthcheck
        node = check.liveliness if check is not None else True
        services[group] = replace(services[group], healthcheck=liveliness(node, GROUP_HEALTH_TIMEOUT_S))
    stack = Stack(
        source=Path(f"zendock {scenario.project}"),
        project_name=scenario.project,
        namespace="",
        connect=(scenario.endpoint,),
        services=services,
    )
    check_stack(stack)
    return apply_replacements(stack, scenario.replacements)


def _robot_services(scenario: Scenario, robot: str) -> dict[str, Params]:
    """One robot's services and their parameters, in :data:`ROBOT_SERVICES` order."""
    world = str(scenario.world)
    keep = scenario.state_dir / robot if scenario.state_dir is not None else None
    own: dict[str, dict[str, object]] = {
        "battery": {"use_sim_time": True, **({"state_file": keep / "battery.json"} if keep else {})},
        "pose": {"use_sim_time": True},
        "planner": {
            "use_sim_time": True,
            "map_yaml": scenario.map_file,
            **({"glass_memory_file": keep / GLASS_MEMORY_FILE} if keep else {}),
        },
        "perception": {"dock_database": world},
        "docking": {"use_sim_time": True, "dock_database": world, "controller": scenario.controller},
    }
    if not DETECTORS[scenario.detector].camera:
        del own["perception"]
    return {name: {**params, **scenario.robot_params.get(name, {})} for name, params in own.items()}


def _service(
    scenario: Scenario,
    name: str,
    params: Params,
    *,
    leading: tuple[str, ...] = (),
    depends_on: Mapping[str, Dependency],
    namespace: str | None = None,
) -> ServiceLaunch:
    """One of zendock's services, restarted on failure, healthy once its node's token is up."""
    return ServiceLaunch(
        ModuleRun(name, (*leading, *param_flags(params))),
        depends_on=depends_on,
        namespace=namespace,
        restart=ON_FAILURE,
        healthcheck=liveliness(name, scenario.health_timeout_s),
    )
