"""``x-robots``: one stack file runs a fleet, each robot's services written once as a template.

    x-robots:
      robots: [r1, r2, r3]
      services:
        battery:
          command: [python, -m, services.battery, -p, use_sim_time=true]
        planner:
          command: [python, -m, services.planner, -p, "glass_memory_file=.zendock/${ROBOT}/glass.npz"]
          depends_on: {map: {condition: service_completed_successfully}, battery: {condition: service_started}}

becomes, for each robot, services ``battery_r1``, ``planner_r1``, ... in namespace ``r1`` (under the
stack's own), with ``${ROBOT}`` replaced by the robot's name everywhere in the template. A dependency on
another template service is on that robot's copy (``planner_r1`` depends on ``battery_r1``); a
dependency on a plain service (``map``, ``simulator``) stays as it is; ``healthcheck: {liveliness: true}``
watches the node named like the template service (``battery`` in namespace ``r1``). ``zendock restart r2/planner``
names ``planner_r2``. The expansion happens before ``${VAR}`` interpolation, so ``${ROBOT}`` is never
looked up in the environment.
"""

from __future__ import annotations

import copy
from typing import Any

from shared.world import ROBOT_NAME

ROBOT_VARIABLE = "${ROBOT}"


class RobotTemplateError(ValueError):
    """An ``x-robots`` block that cannot be expanded; the message says where and why."""


def expand_robots(document: dict[str, Any]) -> dict[str, Any]:
    """The stack document with ``x-robots`` expanded into per-robot services (a new dict)."""
    block = document.get("x-robots")
    if block is None:
        return document
    if not isinstance(block, dict):
        raise RobotTemplateError("x-robots: expected a mapping with 'robots' and 'services'")
    robots, templates = block.get("robots"), block.get("services")
    if not isinstance(robots, list) or not robots or not all(isinstance(r, str) for r in robots):
        raise RobotTemplateError("x-robots.robots: expected a non-empty list of robot names")
    for robot in robots:
        if not ROBOT_NAME.fullmatch(robot):
            raise RobotTemplateError(
                f"x-robots.robots: {robot!r} is not a robot name (a letter, then letters, digits or _)"
            )
    if len(set(robots)) != len(robots):
        raise RobotTemplateError("x-robots.robots: a robot is named twice")
    if not isinstance(templates, dict) or not templates:
        raise RobotTemplateError("x-robots.services: expected a mapping of service templates")
    services = dict(document.get("services") or {})
    for robot in robots:
        for name, template in templates.items():
            where = f"x-robots.services.{name}"
            if not isinstance(template, dict):
                raise RobotTemplateError(f"{where}: expected a mapping")
            expanded = f"{name}_{robot}"
            if expanded in services:
                raise RobotTemplateError(f"{where}: a service is already named {expanded!r}")
            spec = _substitute(copy.deepcopy(template), robot)
            spec.setdefault("namespace", robot)
            check = spec.get("healthcheck")
            if isinstance(check, dict) and check.get("liveliness") is True:
                # The node is named like the template (``battery``), not like its expanded service.
                spec["healthcheck"] = {**check, "liveliness": name}
            spec["depends_on"] = _robot_dependencies(where, spec.get("depends_on"), templates, robot)
            if not spec["depends_on"]:
                del spec["depends_on"]
            services[expanded] = spec
    out = {k: v for k, v in document.items() if k != "x-robots"}
    out["services"] = services
    return out


def service_for(name: str, services: list[str]) -> str:
    """``r2/planner`` -> ``planner_r2`` when that service exists; any other name as it is."""
    robot, sep, service = name.partition("/")
    if sep and f"{service}_{robot}" in services:
        return f"{service}_{robot}"
    return name


def _substitute(value: Any, robot: str) -> Any:
    if isinstance(value, str):
        return value.replace(ROBOT_VARIABLE, robot)
    if isinstance(value, list):
        return [_substitute(v, robot) for v in value]
    if isinstance(value, dict):
        return {k: _substitute(v, robot) for k, v in value.items()}
    return value


def _robot_dependencies(where: str, depends: Any, templates: dict[str, Any], robot: str) -> Any:
    if depends is None:
        return {}
    if isinstance(depends, list):
        return [f"{d}_{robot}" if d in templates else d for d in depends]
    if isinstance(depends, dict):
        return {(f"{d}_{robot}" if d in templates else d): c for d, c in depends.items()}
    raise RobotTemplateError(f"{where}.depends_on: expected a list or a mapping")
