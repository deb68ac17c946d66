"""``--service NAME=COMMAND``: run a user's own program in place of one of zendock's services.

A stack service is zendock's ``NAME`` when its command runs the module ``services.NAME``
(``python -m services.NAME ...``), whatever the stack calls it (``docking``, ``docking_robot1``). Its
replacement keeps everything the launcher gives zendock's own: the environment (``ZENDOCK_CONNECT``,
``ZENDOCK_NAMESPACE``), the stack entry (dependencies, restart policy, health check: the node token
``NAME`` must appear), and the flags after the module name, appended to COMMAND (``-p use_sim_time=true
-p dock_database=...``; the contract says which a replacement may ignore). ``{robot}`` in COMMAND becomes
the service's namespace (``robot1``; empty in a root-namespace stack), for per-robot arguments.

Reports name every replacement and its command (:func:`replacements_report`), so a campaign's figures are
attributable to the code that produced them.
"""

from __future__ import annotations

import os
import shlex
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from deploy.launcher.launch import GroupRun, ModuleRun, ProgramRun
from deploy.launcher.stack_file import Stack, join_namespace
from shared.config_errors import ConfigError

#: The services a user may replace (those with a contract; the router and the one-shot map step are not).
REPLACEABLE = (
    "battery",
    "docking",
    "fleet",
    "perception",
    "planner",
    "pose",
    "ros2_bridge",
    "ros2_dds",
    "simulator",
    "viz",
)
ROBOT_PLACEHOLDER = "{robot}"


@dataclass(frozen=True)
class Replacement:
    """One ``--service NAME=COMMAND``: zendock's service ``name`` replaced by the program ``words``."""

    name: str
    words: tuple[str, ...]

    @classmethod
    def of(cls, name: str, command: str) -> Replacement:
        """From the command as shell text (a stack file's or a report's); :func:`parse_replacement` checks it."""
        return cls(name, tuple(shlex.split(command)))

    @property
    def command(self) -> str:
        """The command as shell text, for reports and for ``--service`` again (a detached ``up``)."""
        return shlex.join(self.words)

    def run_for(self, namespace: str, flags: Sequence[str]) -> ProgramRun:
        """The run of one copy of the service: ``{robot}`` filled in, zendock's flags appended."""
        words = [word.replace(ROBOT_PLACEHOLDER, namespace) for word in self.words]
        return ProgramRun((*words, *flags), replaces=self.name)


def parse_replacement(text: str) -> Replacement:
    """``NAME=COMMAND`` as typed; raises ``ValueError`` with one line saying what is wrong."""
    name, sep, command = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise ValueError(f"expected NAME=COMMAND (e.g. docking='python my_docking.py'), got {text!r}")
    if name not in REPLACEABLE:
        raise ValueError(f"no replaceable service {name!r} (one of: {', '.join(REPLACEABLE)})")
    try:
        words = shlex.split(command)
    except ValueError as exc:
        raise ValueError(f"--service {name}: the command does not parse as shell words: {exc}") from None
    if not words:
        raise ValueError(f"--service {name}: the command is empty")
    # A file named relative to where the user typed it: zendock runs services in another directory.
    return Replacement(name, tuple(absolute_if_file(word) for word in words))


def absolute_if_file(word: str) -> str:
    """A word naming an existing file here (``my_docking.py``, ``./bin/dock``), as an absolute path; others as
    they are. ``abspath``, not ``resolve``: a venv's python is a symlink that must stay the venv's."""
    path = Path(word)
    return os.path.abspath(path) if not path.is_absolute() and path.is_file() else word


def check_unique(replacements: Iterable[Replacement], option: str = "--service") -> list[Replacement]:
    """The replacements, refusing two for the same service (``option`` names where they were given)."""
    seen: dict[str, Replacement] = {}
    for replacement in replacements:
        if replacement.name in seen:
            raise ValueError(f"{option} {replacement.name} is given twice")
        seen[replacement.name] = replacement
    return list(seen.values())


def apply_replacements(stack: Stack, replacements: Sequence[Replacement]) -> Stack:
    """``stack`` with every copy of each replaced service running the replacement's command.

    Raises :class:`ConfigError` when a replaced service is not in the stack, or runs inside a composed
    ``zendock container`` process (replace it in a stack that runs it as its own process).
    """
    if not replacements:
        return stack
    services = dict(stack.services)
    try:
        unique = check_unique(replacements)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    for replacement in unique:
        found = 0
        for service_name, launch in stack.services.items():
            run = launch.run
            if isinstance(run, GroupRun) and replacement.name in run.services:
                raise ConfigError(
                    f"--service {replacement.name}: {service_name} runs it inside a composed zendock container; "
                    "replace it in a stack that runs it as its own process"
                )
            if not (isinstance(run, ModuleRun) and run.service == replacement.name):
                continue
            namespace = join_namespace(stack.namespace, launch.namespace)
            services[service_name] = replace(launch, run=replacement.run_for(namespace, run.flags))
            found += 1
        if not found:
            raise ConfigError(
                f"--service {replacement.name}: the stack {stack.source} runs no services.{replacement.name}"
            )
    return replace(stack, services=services)


def replacements_report(replacements: Sequence[Replacement]) -> dict[str, str]:
    """What reports record: each replaced service and the command that ran instead (``{}`` if none)."""
    return {r.name: r.command for r in replacements}
