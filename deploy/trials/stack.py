"""The stack a campaign runs: one simulator for every robot, each robot's own services."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from deploy.trials.records import TrialOptions

#: Each robot's planner keeps its glass memory in ``<state_dir>/<robot>/`` under this name.
GLASS_MEMORY_FILE = "glass_memory.npz"


def trials_stack(options: TrialOptions, endpoint: str, robots: list[str], state_dir: Path | None = None) -> dict[str, Any]:
    """A stack file (as data) with one simulator for all robots and each robot's own services.

    ``state_dir``: where each robot's planner keeps its glass memory and its battery its charge across
    restarts (``--chaos``).
    """
    world = str(options.world)
    py = ["python", "-m"]
    services: dict[str, Any] = {
        "router": {"command": ["zendock", "router", "--listen", endpoint], "restart": "on-failure"},
        "map": {"command": ["zendock", "map", "save", "--world", world, "-o", ".zendock/maps/map.yaml"], "restart": "no"},
        "simulator": {
            "command": [*py, "services.simulator", "--world", world, "-p", f"rtf={options.rtf}",
                        "-p", f"seed={options.seed}", "-p", f"robots={json.dumps(robots)}",
                        "-p", f"localisation_error={json.dumps(list(options.localisation_error))}",
                        "-p", f"dock_detector={options.detector}"],
            "depends_on": {"router": {"condition": "service_started"}},
            "healthcheck": {"liveliness": True, "timeout": "30s"},
            "restart": "on-failure",
        },
    }
    for robot in robots:
        common = {"depends_on": {"router": {"condition": "service_started"}}, "namespace": robot,
                  "restart": "on-failure"}

        def health(node: str) -> dict[str, Any]:
            return {"healthcheck": {"liveliness": node, "timeout": "30s"}}

        keep_charge = ["-p", f"state_file={state_dir / robot / 'battery.json'}"] if state_dir else []
        services[f"battery_{robot}"] = {**common, **health("battery"),
                                        "command": [*py, "services.battery", "-p", "use_sim_time=true", *keep_charge]}
        services[f"pose_{robot}"] = {**common, **health("pose"), "command": [*py, "services.pose", "-p", "use_sim_time=true"]}
        services[f"planner_{robot}"] = {
            **common,
            **health("planner"),
            "command": [*py, "services.planner", "-p", "use_sim_time=true", "-p", "map_yaml=.zendock/maps/map.yaml",
                        *(["-p", f"glass_memory_file={state_dir / robot / GLASS_MEMORY_FILE}"] if state_dir else [])],
            "depends_on": {"router": {"condition": "service_started"},
                           "map": {"condition": "service_completed_successfully"}},
        }
        if options.detector == "aruco":
            services[f"perception_{robot}"] = {**common, **health("perception"),
                                               "command": [*py, "services.perception", "-p", f"dock_database={world}"]}
        services[f"docking_{robot}"] = {
            **common,
            **health("docking"),
            "command": [*py, "services.docking", "-p", "use_sim_time=true", "-p", f"dock_database={world}",
                        "-p", f"controller={options.controller}"],
        }
    return {"name": "trials", "namespace": "", "zenoh": {"connect": [endpoint]}, "services": services}
