"""The typed launch model: what a service runs, read once from its command, and the service around it.

A stack file's ``command`` is a list of words, as in Compose. The launcher reads those words once, here,
into one of three runs:

- :class:`ModuleRun`: one of zendock's services, ``python -m services.<service> FLAGS``;
- :class:`GroupRun`: several of them in one process and one session (``zendock container A + B ...``);
- :class:`ProgramRun`: any other program (the router, the map step, a user's own service).

Everything after works on these types: a replacement (``--service``) turns a :class:`ModuleRun` into a
:class:`ProgramRun` that stands in for it, composition (``x-compose``, ``--compose``) folds module runs into a
:class:`GroupRun`, conform and export ask a run which service it is. Words are produced again only where a
process starts (:func:`run_words`), so no other module reads argv to learn what a service is.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Annotated, Literal

import msgspec

from deploy.launcher.restart import RestartPolicy

#: Dependency conditions, as in Compose.
Condition = Literal["service_started", "service_healthy", "service_completed_successfully"]
#: A service's, a project's or a node's name.
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
DEFAULT_STOP_GRACE_S = 5.0
#: Seconds. A stack file writes ``5s`` or ``500ms``: :mod:`deploy.launcher.stack_file` reads that text
#: (:func:`~deploy.launcher.durations.parse_duration`) before it validates the file.
Duration = Annotated[float, msgspec.Meta(ge=0)]

#: The package zendock's services live in: ``python -m services.<name>``.
SERVICES_PACKAGE = "services"
#: ``zendock container``'s word between two members.
GROUP_SEPARATOR = "+"
#: ``zendock container``'s own options that take a value (they may stand before the first member).
GROUP_VALUE_OPTIONS = frozenset({"--namespace", "--connect", "--zenoh-config", "--log-level"})


@dataclass(frozen=True)
class ModuleRun:
    """One of zendock's services: ``python -m services.<service> FLAGS``.

    ``python`` is the interpreter word: ``python`` (the launcher's own) or another (the DDS face runs with
    ``.venv-ros2/bin/python``); ``python_options`` are the interpreter's own, before ``-m`` (``-u``).
    """

    service: str
    flags: tuple[str, ...] = ()
    python: str = "python"
    python_options: tuple[str, ...] = ()


@dataclass(frozen=True)
class GroupRun:
    """Several of zendock's services in one process on one session (``zendock container``).

    ``options`` are the container's own (``--namespace r1``), given before the first member; ``program`` is
    the zendock that runs them (``zendock``: the launcher's own; a path: that one).
    """

    members: tuple[ModuleRun, ...]
    options: tuple[str, ...] = ()
    program: str = "zendock"

    @property
    def services(self) -> tuple[str, ...]:
        return tuple(member.service for member in self.members)


@dataclass(frozen=True)
class ProgramRun:
    """Any other program, as its words. ``replaces`` names the zendock service it stands in for (``--service``)."""

    words: tuple[str, ...]
    replaces: str | None = None


Run = ModuleRun | GroupRun | ProgramRun


def read_command(words: Sequence[str]) -> Run:
    """The run a stack file's command words describe (the one place those words are read)."""
    words = tuple(str(word) for word in words)
    # An interpreter, its own options (``-u``, ``-X importtime``: words before ``-m``), then the module.
    at = words.index("-m") if "-m" in words else -1
    if (
        at >= 1
        and at + 1 < len(words)
        and _is_service_module(words[at + 1])
        and _interpreter_options(words[1:at])
    ):
        service = words[at + 1].removeprefix(f"{SERVICES_PACKAGE}.")
        return ModuleRun(service, words[at + 2 :], words[0], words[1:at])
    if len(words) >= 2 and words[1] == "container" and words[0].rsplit("/", 1)[-1] == "zendock":
        group = _read_group(words[2:])
        if group is not None:
            return GroupRun(group.members, group.options, words[0])
    return ProgramRun(words)


def _interpreter_options(words: Sequence[str]) -> bool:
    """Whether ``words`` can be an interpreter's options: each an option or the value after ``-X``/``-W``."""
    expect_value = False
    for word in words:
        if expect_value:
            expect_value = False
        elif word in ("-X", "-W"):
            expect_value = True
        elif not word.startswith("-"):
            return False
    return not expect_value


def _is_service_module(module: str) -> bool:
    package, dot, name = module.partition(".")
    return package == SERVICES_PACKAGE and bool(dot) and name.isidentifier()


def _read_group(words: Sequence[str]) -> GroupRun | None:
    """``[OPTIONS] A ARGS + B ARGS ...``; ``None`` when no member is named."""
    options: list[str] = []
    index = 0
    while index < len(words) and words[index].startswith("-"):
        takes_value = words[index] in GROUP_VALUE_OPTIONS
        options += words[index : index + (2 if takes_value else 1)]
        index += 2 if takes_value else 1
    members: list[ModuleRun] = []
    current: list[str] = []
    for word in (*words[index:], GROUP_SEPARATOR):
        if word != GROUP_SEPARATOR:
            current.append(word)
            continue
        if not current or not current[0].isidentifier():
            return None
        members.append(ModuleRun(current[0], tuple(current[1:])))
        current = []
    return GroupRun(tuple(members), tuple(options))


def run_words(run: Run) -> list[str]:
    """The words that start ``run`` (``python`` and ``zendock`` are resolved where the process starts)."""
    if isinstance(run, ModuleRun):
        return _module_words(run, f"{SERVICES_PACKAGE}.{run.service}")
    if isinstance(run, GroupRun):
        words = [run.program, "container", *run.options]
        for i, member in enumerate(run.members):
            words += [*([GROUP_SEPARATOR] if i else []), member.service, *member.flags]
        return words
    return list(run.words)


#: The program a warm standby runs (:mod:`deploy.standby`): it imports a service, then waits to become it.
STANDBY_MODULE = "deploy.standby"


def standby_words(run: Run) -> list[str] | None:
    """The words of a warm standby for ``run``: one of zendock's services on the launcher's own interpreter
    (a standby imports that interpreter's packages). None for anything else: a group, a program, a service on
    another interpreter (the DDS face)."""
    if not isinstance(run, ModuleRun) or run.python != "python":
        return None
    return _module_words(run, STANDBY_MODULE, f"{SERVICES_PACKAGE}.{run.service}")


def _module_words(run: ModuleRun, *module: str) -> list[str]:
    """``python [OPTIONS] -m MODULE... FLAGS``: the service itself, or a standby naming it."""
    return [run.python, *run.python_options, "-m", *module, *run.flags]


def as_text(value: object) -> str:
    """A YAML scalar as a command word or a variable's value (``true``, ``8``, ``0.5``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (str, int, float)):
        return str(value)
    raise ValueError(f"expected text or a number, got {value!r}")


class Strict(msgspec.Struct, forbid_unknown_fields=True, frozen=True, kw_only=True):
    """A stack file's section: unknown keys are errors, values are frozen.

    Checked where a stack file comes in (:func:`deploy.launcher.stack_file.validate_stack_file`); one built in
    Python by its constructor (the runners' stacks) runs only its ``__post_init__``, as a dataclass would.
    """


class Dependency(Strict, frozen=True):
    condition: Condition = "service_started"


class Healthcheck(Strict, frozen=True):
    """Healthy when the service's liveliness token is up and/or an exec test passes.

    ``liveliness: true`` watches the token of the node named like the service (a string names the node);
    ``timeout`` is then how long the service has to declare it before it counts as unhealthy. ``test``
    runs a command every ``interval`` (``timeout`` per run); ``retries`` failures in a row make it unhealthy.
    """

    liveliness: bool | str = False
    test: list[str] | str | None = None
    interval: Duration = 2.0
    timeout: Duration | None = None
    retries: Annotated[int, msgspec.Meta(ge=1)] = 3
    start_period: Duration = 0.0
    disable: bool = False

    def __post_init__(self) -> None:
        if not self.disable and not self.liveliness and not self.test:
            raise ValueError("give liveliness: true or a test command (or disable: true)")
        if isinstance(self.liveliness, str) and not NAME_RE.match(self.liveliness):
            raise ValueError(f"liveliness: {self.liveliness!r} is not a node name")

    @property
    def enabled(self) -> bool:
        return not self.disable and bool(self.liveliness or self.test)


@dataclass(frozen=True)
class ServiceLaunch:
    """One service of a stack: what runs, where, after what, how it is watched and restarted.

    Built from a stack file (:func:`deploy.launcher.stack_file.load_stack`) or directly in Python by the
    runners (trials, fleets); the keys and meanings follow the Compose specification.
    """

    run: Run
    depends_on: Mapping[str, Dependency] = field(default_factory=dict)
    restart: RestartPolicy = RestartPolicy("no")
    healthcheck: Healthcheck | None = None
    #: Relative to the stack's namespace, unless it starts with ``/``.
    namespace: str | None = None
    environment: Mapping[str, str | None] = field(default_factory=dict)
    profiles: tuple[str, ...] = ()
    stop_grace_period: float = DEFAULT_STOP_GRACE_S
    working_dir: str | None = None

    @property
    def command(self) -> list[str]:
        """The run as stack-file words (``zendock config``, exports, reports)."""
        return run_words(self.run)

    @property
    def members(self) -> tuple[str, ...]:
        """For a group, the services its one process runs (``zendock ps`` shows them)."""
        return self.run.services if isinstance(self.run, GroupRun) else ()


def after(**conditions: Condition) -> dict[str, Dependency]:
    """``after(router="service_started")``: a ``depends_on`` map, for stacks built in Python."""
    return {name: Dependency(condition=condition) for name, condition in conditions.items()}


def liveliness(node: str | bool = True, timeout_s: float = 30.0) -> Healthcheck:
    """Healthy once the node's liveliness token is up (``True``: the node named like the service)."""
    return Healthcheck(liveliness=node, timeout=timeout_s)


def param_flags(values: Mapping[str, object]) -> tuple[str, ...]:
    """``-p name=value`` for each parameter, as a service's command line takes them: a list or a tuple as
    JSON, a bool as ``true``/``false``, anything else as its text."""
    flags: list[str] = []
    for name, value in values.items():
        if isinstance(value, bool):
            text = "true" if value else "false"
        elif isinstance(value, (list, tuple)):
            text = json.dumps(list(value))
        else:
            text = str(value)
        flags += ["-p", f"{name}={text}"]
    return tuple(flags)
