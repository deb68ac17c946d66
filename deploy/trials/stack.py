"""The stack a campaign runs: one simulator for every robot, each robot's own services."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from deploy.launcher.composition import members_to_compose
from deploy.trials.records import TrialOptions
from shared.controllers import DETECTORS

#: Each robot's planner keeps its glass memory in ``<state_dir>/<robot>/`` under this name.
GLASS_MEMORY_FILE = "glass_memory.npz"


def trials_stack(
    options: TrialOptions, endpoint: str, robots: list[str], state_dir: Path | None = None
) -> dict[str, Any]:
    """A stack file (as data) with one simulator for all robots and each robot's own services.

    ``state_dir``: where each robot's planner keeps its glass memory and its battery its charge across
    restarts (``--chaos``).
    """
    world = str(options.world)
    # the campaign's own map (in its state directory): other stacks in this checkout never read it
    map_file = str(state_dir / "map.yaml") if state_dir else ".zendock/maps/map.yaml"
    py = ["python", "-m"]
    services: dict[str, Any] = {
        "router": {"command": ["zendock", "router", "--listen", endpoint], "restart": "on-failure"},
        "map": {"command": ["zendock", "map", "save", "--world", world, "-o", map_file], "restart": "no"},
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
                f"robots={json.dumps(robots)}",
                "-p",
                f"localisation.error={json.dumps(list(options.localisation_error))}",
                "-p",
                f"detection.source={options.detector}",
            ],
            "depends_on": {"router": {"condition": "service_started"}},
            "healthcheck": {"liveliness": True, "timeout": "30s"},
            "restart": "on-failure",
        },
    }
    for robot in robots:
        keep_charge = ["-p", f"state_file={state_dir / robot / 'battery.json'}"] if state_dir else []
        members: dict[str, list[str]] = {
            "battery": ["-p", "use_sim_time=true", *keep_charge],
            "pose": ["-p", "use_sim_time=true"],
            "planner": [
                "-p",
                "use_sim_time=true",
                "-p",
                f"map_yaml={map_file}",
                *(["-p", f"glass_memory_file={state_dir / robot / GLASS_MEMORY_FILE}"] if state_dir else []),
            ],
        }
        if DETECTORS[options.detector].camera:
            members["perception"] = ["-p", f"dock_database={world}"]
        members["docking"] = [
            "-p",
            "use_sim_time=true",
            "-p",
            f"dock_database={world}",
            "-p",
            f"controller={options.controller}",
        ]
        common: dict[str, Any] = {
            "depends_on": {"router": {"condition": "service_started"}},
            "namespace": robot,
            "restart": "on-failure",
        }
        after_map = {
            "depends_on": {
                "router": {"condition": "service_started"},
                "map": {"condition": "service_completed_successfully"},
            }
        }
        grouped = {
            n: members[n]
            for n in members_to_compose(members, options.compose, {r.name for r in options.replacements})
        }
        if grouped:
            # The robot's services (all, or the light ones) share a process and a session (zendock
            # container); the group is healthy once its last member is up.
            command = ["zendock", "container"]
            for i, (name, args) in enumerate(grouped.items()):
                command += [*(["+"] if i else []), name, *args]
            services[f"robot_{robot}"] = {
                **common,
                **(after_map if "planner" in grouped else {}),
                "command": command,
                "healthcheck": {"liveliness": list(grouped)[-1], "timeout": "60s"},
            }
            members = {n: a for n, a in members.items() if n not in grouped}
        for name, args in members.items():
            services[f"{name}_{robot}"] = {
                **common,
                **(after_map if name == "planner" else {}),
                "healthcheck": {"liveliness": name, "timeout": "30s"},
                "command": [*py, f"services.{name}", *args],
            }
    return {"name": "trials", "namespace": "", "zenoh": {"connect": [endpoint]}, "services": services}
