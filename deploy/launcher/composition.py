"""Composition: a stack's groups of services that run as one process (``zendock container``).

    x-compose:
      robot: [battery, pose, planner, perception, docking]

Each member is one of zendock's services (a :class:`~deploy.launcher.launch.ModuleRun`) with its own entry in
the stack; the group replaces them with one service of the group's name whose run is a
:class:`~deploy.launcher.launch.GroupRun` of the members' runs. The group depends on what its members
depended on (outside the group), is healthy when its last member's node is, restarts by its first member's
policy and stops within the longest grace period; services that depended on a member depend on the group.
Without groups nothing changes: every service is its own process, as by default. ``--compose`` (trials,
fleets) names the groups with :func:`members_to_compose`; a stack file with ``x-compose``.
"""

from __future__ import annotations

from collections.abc import Container, Iterable, Mapping
from dataclasses import replace
from typing import Any

from deploy.launcher.launch import (
    Condition,
    Dependency,
    GroupRun,
    Healthcheck,
    ModuleRun,
    ServiceLaunch,
)

#: What ``--compose light`` puts in one process (trials, fleets): the services that do little per message.
LIGHT_SERVICES = ("battery", "pose")


def members_to_compose(names: Iterable[str], compose: str, replaced: Container[str]) -> list[str]:
    """Which of a robot's services ``--compose`` puts in its one process: all of them (``all``), the light
    ones (``light``) or none (``""``); a replaced service keeps a process of its own (a user's program is
    not a zendock container member)."""
    return [
        name
        for name in names
        if name not in replaced and (compose == "all" or (compose == "light" and name in LIGHT_SERVICES))
    ]


#: When two members depend on the same service with different conditions, the strictest holds.
_STRICTNESS: dict[Condition, int] = {
    "service_started": 0,
    "service_healthy": 1,
    "service_completed_successfully": 2,
}


class CompositionError(ValueError):
    """A group that cannot run as one process; the message names the group and the reason."""


def compose_groups(
    services: Mapping[str, ServiceLaunch], groups: Mapping[str, Any]
) -> dict[str, ServiceLaunch]:
    """``services`` with each group's members replaced by the group (a new mapping; input untouched)."""
    out = dict(services)
    grouped: dict[str, str] = {}
    for group, members in groups.items():
        where = f"x-compose.{group}"
        if not isinstance(members, list) or not members or not all(isinstance(m, str) for m in members):
            raise CompositionError(f"{where}: expected a non-empty list of service names")
        if group in out:
            raise CompositionError(f"{where}: a service is already named {group!r}")
        for member in members:
            if member in grouped:
                raise CompositionError(f"{where}: {member!r} is already in group {grouped[member]!r}")
            if member not in out:
                raise CompositionError(f"{where}: unknown service {member!r}")
            grouped[member] = group
        out[group] = _group_service(where, [(m, out[m]) for m in members], set(members))
        for member in members:
            del out[member]
    for name, launch in out.items():
        if any(d in grouped for d in launch.depends_on):
            out[name] = replace(
                launch, depends_on=_merge_depends([launch.depends_on], grouped, exclude={name})
            )
    return out


def _group_service(where: str, members: list[tuple[str, ServiceLaunch]], names: set[str]) -> ServiceLaunch:
    runs: list[ModuleRun] = []
    for name, launch in members:
        if (
            not isinstance(launch.run, ModuleRun)
            or launch.run.python != "python"
            or launch.run.python_options
        ):
            raise CompositionError(
                f"{where}: {name}'s command is not 'python -m services.<name> ...': "
                "only zendock's services run in a container"
            )
        runs.append(launch.run)
    namespaces = {launch.namespace for _, launch in members}
    if len(namespaces) > 1:
        raise CompositionError(
            f"{where}: the members have different namespaces {sorted(map(str, namespaces))}"
        )
    first = members[0][1]
    # The group is healthy when its last member's node is: the node its own check watches when it names one
    # (a robot's ``docking_r1`` is the node ``docking``), else the node named like the service.
    last_name, last = members[-1]
    watched = last.healthcheck.liveliness if last.healthcheck is not None else None
    timeouts = [m.healthcheck.timeout for _, m in members if m.healthcheck is not None]
    environment: dict[str, str | None] = {}
    for _, member in members:
        environment.update(member.environment)
    return ServiceLaunch(
        run=GroupRun(tuple(runs)),
        depends_on=_merge_depends([m.depends_on for _, m in members], {}, exclude=names),
        restart=first.restart,
        healthcheck=Healthcheck(
            liveliness=watched if isinstance(watched, str) else last_name,
            timeout=timeouts[-1] if timeouts else None,
        ),
        namespace=first.namespace,
        environment=environment,
        profiles=first.profiles,
        stop_grace_period=max(m.stop_grace_period for _, m in members),
        working_dir=first.working_dir,
    )


def _merge_depends(
    all_depends: Iterable[Mapping[str, Dependency]], grouped: Mapping[str, str], exclude: set[str]
) -> dict[str, Dependency]:
    merged: dict[str, Dependency] = {}
    for depends in all_depends:
        for dependency, condition in depends.items():
            target = grouped.get(dependency, dependency)
            if target in exclude:
                continue
            known = merged.get(target)
            if known is None or _STRICTNESS[condition.condition] > _STRICTNESS[known.condition]:
                merged[target] = condition
    return merged
