"""``x-compose``: a stack file's groups of services that run as one process (``zendock container``).

    x-compose:
      robot: [battery, pose, planner, perception, docking]

Each member keeps its own entry in ``services`` (its ``python -m services.<name> ARGS`` command, its
parameters); the group replaces them with one service of the group's name whose command is
``zendock container <name> ARGS + <name> ARGS ...``. The group depends on what its members depended on
(outside the group), is healthy when its last member's node is, restarts by its first member's policy and
stops within the longest grace period; services that depended on a member depend on the group. Without
``x-compose`` nothing changes: every service is its own process, as by default.
"""

from __future__ import annotations

import shlex
from collections.abc import Container, Iterable
from typing import Any

from deploy.launcher.durations import parse_duration

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
_STRICTNESS = {"service_started": 0, "service_healthy": 1, "service_completed_successfully": 2}


class CompositionError(ValueError):
    """A group that cannot run as one process; the message names the group and the reason."""


def compose_groups(document: dict[str, Any], groups: dict[str, Any]) -> dict[str, Any]:
    """The stack document with each group's members replaced by the group (a new dict; input untouched)."""
    if not isinstance(groups, dict):
        raise CompositionError("x-compose: expected a mapping of group names to lists of services")
    services = dict(document.get("services") or {})
    grouped: dict[str, str] = {}
    for group, members in groups.items():
        where = f"x-compose.{group}"
        if not isinstance(members, list) or not members or not all(isinstance(m, str) for m in members):
            raise CompositionError(f"{where}: expected a non-empty list of service names")
        if group in services:
            raise CompositionError(f"{where}: a service is already named {group!r}")
        for member in members:
            if member in grouped:
                raise CompositionError(f"{where}: {member!r} is already in group {grouped[member]!r}")
            if member not in services:
                raise CompositionError(f"{where}: unknown service {member!r}")
            grouped[member] = group
        services[group] = _group_service(where, group, [(m, services[m]) for m in members], set(members))
        for member in members:
            del services[member]
    for name, spec in services.items():
        depends = spec.get("depends_on") if isinstance(spec, dict) else None
        if isinstance(depends, dict) and any(d in grouped for d in depends):
            services[name] = {**spec, "depends_on": _merge_depends([depends], grouped, exclude={name})}
        elif isinstance(depends, list) and any(d in grouped for d in depends):
            services[name] = {**spec, "depends_on": sorted({grouped.get(d, d) for d in depends} - {name})}
    return {**document, "services": services}


#: ``zendock container``'s own options that take a value (they may come before the first service).
_CONTAINER_VALUE_OPTIONS = {"--namespace", "--connect", "--listen", "--zenoh-config", "--log-level"}


def container_members(command: list[str] | tuple[str, ...]) -> tuple[str, ...]:
    """The services a ``zendock container A ARGS + B ARGS ...`` command runs (empty for any other command),
    so ``zendock ps`` can say which services a group's process carries and restarts with it."""
    words = [str(w) for w in command]
    if len(words) < 3 or words[1] != "container" or not words[0].endswith("zendock"):
        return ()
    members, expect_name, skip = [], True, False
    for word in words[2:]:
        if skip:
            skip = False
        elif word == "+":
            expect_name = True
        elif expect_name and word in _CONTAINER_VALUE_OPTIONS:
            skip = True
        elif expect_name and not word.startswith("-"):
            members.append(word)
            expect_name = False
    return tuple(members)


def _group_service(where: str, group: str, members: list[tuple[str, Any]], names: set[str]) -> dict[str, Any]:
    command = ["zendock", "container"]
    namespaces = set()
    for i, (name, spec) in enumerate(members):
        if not isinstance(spec, dict):
            raise CompositionError(f"{where}: services.{name} is not a mapping")
        words = spec.get("command")
        words = shlex.split(words) if isinstance(words, str) else list(words or [])
        if len(words) < 3 or words[:2] != ["python", "-m"] or not words[2].startswith("services."):
            raise CompositionError(
                f"{where}: {name}'s command is not 'python -m services.<name> ...': "
                "only zendock's services run in a container"
            )
        command += [*(["+"] if i else []), words[2].removeprefix("services."), *[str(w) for w in words[3:]]]
        namespaces.add(spec.get("namespace"))
    if len(namespaces) > 1:
        raise CompositionError(
            f"{where}: the members have different namespaces {sorted(map(str, namespaces))}"
        )
    first = members[0][1]
    # The group is healthy when its last member's node is: the node its own check watches when it names one
    # (a robot template's ``docking_r1`` is the node ``docking``), else the node named like the service.
    last_check = members[-1][1].get("healthcheck")
    watched = last_check.get("liveliness") if isinstance(last_check, dict) else None
    last_name = watched if isinstance(watched, str) else members[-1][0]
    timeouts = [
        m.get("healthcheck", {}).get("timeout") for _, m in members if isinstance(m.get("healthcheck"), dict)
    ]
    service: dict[str, Any] = {
        "command": command,
        "depends_on": _merge_depends([m.get("depends_on") or {} for _, m in members], {}, exclude=names),
        "healthcheck": {"liveliness": last_name, **({"timeout": timeouts[-1]} if timeouts else {})},
    }
    for key in ("restart", "namespace", "profiles", "working_dir"):
        if key in first:
            service[key] = first[key]
    environment: dict[str, Any] = {}
    for _, member in members:
        env = member.get("environment") or {}
        if isinstance(env, list):
            env = dict(item.partition("=")[::2] for item in env)
        environment.update(env)
    if environment:
        service["environment"] = environment
    graces = [m["stop_grace_period"] for _, m in members if "stop_grace_period" in m]
    if graces:
        service["stop_grace_period"] = max(graces, key=parse_duration)
    return service


def _merge_depends(all_depends: list[Any], grouped: dict[str, str], exclude: set[str]) -> dict[str, Any]:
    merged: dict[str, Any] = {}
    for depends in all_depends:
        items = {d: {} for d in depends} if isinstance(depends, list) else dict(depends)
        for dependency, condition in items.items():
            target = grouped.get(dependency, dependency)
            if target in exclude:
                continue
            condition = condition or {}
            known = merged.get(target)
            if known is None or _STRICTNESS.get(
                condition.get("condition", "service_started"), 0
            ) > _STRICTNESS.get(known.get("condition", "service_started"), 0):
                merged[target] = condition
    return merged
