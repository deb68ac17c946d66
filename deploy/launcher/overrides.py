"""Parameter overrides of a typed stack: ``zendock up --set docking.auto_dock=false``, a demo's controller.

An override sets ``-p NAME=VALUE`` on every copy of one of zendock's services (alone or inside a composed
group), replacing the value the stack gave it: it changes the typed run, so a replacement applied after it
(``--service``) gets the overridden flags as zendock's own service would.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from deploy.launcher.launch import GroupRun, ModuleRun, Run, param_flags
from deploy.launcher.stack_file import Stack
from shared.config_errors import ConfigError
from shared.suggestions import did_you_mean


def _with_values(run: ModuleRun, values: Mapping[str, object]) -> ModuleRun:
    flags = list(run.flags)
    kept: list[str] = []
    i = 0
    while i < len(flags):
        if flags[i] == "-p" and i + 1 < len(flags) and flags[i + 1].split("=", 1)[0] in values:
            i += 2  # the stack's own value: replaced below
            continue
        kept.append(flags[i])
        i += 1
    return ModuleRun(run.service, (*kept, *param_flags(values)), run.python, run.python_options)


def _overridden(run: Run, service: str, values: Mapping[str, object]) -> Run | None:
    if isinstance(run, ModuleRun) and run.service == service:
        return _with_values(run, values)
    if isinstance(run, GroupRun) and service in run.services:
        members = tuple(_with_values(m, values) if m.service == service else m for m in run.members)
        return GroupRun(members, run.options, run.program)
    return None


def with_params(stack: Stack, service: str, values: Mapping[str, object]) -> Stack:
    """``stack`` with ``values`` as parameters of every copy of zendock's ``service``; a
    :class:`ConfigError` when the stack runs no such service."""
    if not values:
        return stack
    services = dict(stack.services)
    found = False
    for name, launch in stack.services.items():
        run = _overridden(launch.run, service, values)
        if run is not None:
            services[name] = replace(launch, run=run)
            found = True
    if not found:
        known = sorted({m.service for launch in stack.services.values() for m in _module_runs(launch.run)})
        raise ConfigError(
            f"--set {service}: the stack runs no zendock service {service!r}{did_you_mean(service, known)} "
            f"(it runs: {', '.join(known)})"
        )
    return replace(stack, services=services)


def _module_runs(run: Run) -> tuple[ModuleRun, ...]:
    if isinstance(run, ModuleRun):
        return (run,)
    if isinstance(run, GroupRun):
        return run.members
    return ()


def parse_set(text: str) -> tuple[str, str, str]:
    """``SERVICE.NAME=VALUE`` (``docking.auto_dock=false``) as ``(service, name, value)``; a ``ValueError``
    with one line otherwise. The value stays text: the service parses it as it parses ``-p``."""
    target, sep, value = text.partition("=")
    service, dot, name = target.partition(".")
    if not sep or not dot or not service or not name:
        raise ValueError(f"expected SERVICE.PARAMETER=VALUE (e.g. docking.auto_dock=false), got {text!r}")
    return service.strip(), name.strip(), value


def apply_sets(stack: Stack, sets: list[tuple[str, str, str]]) -> Stack:
    """Every ``--set``, grouped by service (a later one for the same parameter wins)."""
    by_service: dict[str, dict[str, object]] = {}
    for service, name, value in sets:
        by_service.setdefault(service, {})[name] = value
    for service, values in by_service.items():
        stack = with_params(stack, service, values)
    return stack
