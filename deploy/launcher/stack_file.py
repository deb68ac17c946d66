"""The stack file: a Compose-like YAML description of the services to run, strictly validated.

Validation happens once, here: unknown keys and bad values are :class:`ConfigError`\\ s whose lines read
``FILE: services.planner.restart: reason``. Keys starting with ``x-`` are extensions and are ignored,
at the top level and in a service, as in Compose.

Compose's short forms (a command as one string, ``environment`` and ``depends_on`` as lists, durations as
``5s``, ``restart: on-failure:3``) are read into the records' own forms first, by one small function per key
(:func:`validate_stack_file`); the records (msgspec ``Struct``\\ s) then check types, bounds and unknown keys.
"""

from __future__ import annotations

import os
import re
import shlex
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Annotated, Any

import msgspec
import yaml

from deploy.launcher.composition import CompositionError, compose_groups
from deploy.launcher.durations import format_duration, parse_duration
from deploy.launcher.graph import dependency_order, find_cycle, with_dependencies
from deploy.launcher.launch import (
    DEFAULT_STOP_GRACE_S,
    NAME_RE,
    Dependency,
    Duration,
    Healthcheck,
    ServiceLaunch,
    Strict,
    as_text,
    read_command,
)
from deploy.launcher.restart import RestartPolicy, parse_restart_policy
from deploy.launcher.robot_template import RobotTemplateError, expand_robots
from shared.config_errors import ConfigError
from shared.interpolation import InterpolationError, interpolate_tree, parse_env_file
from shared.names import normalise_namespace
from shared.session import DEFAULT_ROUTER_ENDPOINT
from shared.structs import blaming, validate
from shared.suggestions import no_such

DEFAULT_CONNECT = f"${{ZENOH_CONNECT:-{DEFAULT_ROUTER_ENDPOINT}}}"
DEFAULT_LIVELINESS_TIMEOUT_S = 30.0
DEFAULT_CHECK_TIMEOUT_S = 5.0


class ServiceSpec(Strict, frozen=True):
    """One service as the stack file writes it; keys and meanings follow the Compose specification.

    Read into a :class:`~deploy.launcher.launch.ServiceLaunch` (:meth:`launch`) once validated: its command
    words become a typed run there.
    """

    command: list[str]
    working_dir: str | None = None
    environment: dict[str, str | None] = msgspec.field(default_factory=dict)
    depends_on: dict[str, Dependency] = msgspec.field(default_factory=dict)
    restart: RestartPolicy = RestartPolicy("no")
    healthcheck: Healthcheck | None = None
    profiles: list[str] = msgspec.field(default_factory=list)
    stop_grace_period: Duration = DEFAULT_STOP_GRACE_S
    namespace: str | None = None

    def __post_init__(self) -> None:
        if not self.command:
            raise ValueError("command: must not be empty")
        if self.namespace is not None:
            _check_namespace(self.namespace)

    def launch(self) -> ServiceLaunch:
        return ServiceLaunch(
            run=read_command(self.command),
            depends_on=dict(self.depends_on),
            restart=self.restart,
            healthcheck=self.healthcheck,
            namespace=self.namespace,
            environment=dict(self.environment),
            profiles=tuple(self.profiles),
            stop_grace_period=self.stop_grace_period,
            working_dir=self.working_dir,
        )


class ZenohSettings(Strict, frozen=True):
    """Where services and the launcher's health checker connect (``ZENDOCK_CONNECT`` of every service).

    ``connect``: endpoints, each item possibly several separated by commas (``${ZENOH_CONNECT}``).
    ``config``: a Zenoh json5 file for the launcher's own session (the health checker), e.g. the
    credentials a secured router asks for; relative to the directory services run in.
    """

    connect: list[str] = msgspec.field(default_factory=lambda: [DEFAULT_ROUTER_ENDPOINT])
    config: str | None = None

    def __post_init__(self) -> None:
        endpoints = [part.strip() for item in self.connect for part in item.split(",") if part.strip()]
        if not endpoints:
            raise ValueError("connect: give at least one endpoint, e.g. tcp/127.0.0.1:7447")
        msgspec.structs.force_setattr(self, "connect", endpoints)


class StackFile(Strict, frozen=True, kw_only=True):
    name: str | None = None
    namespace: str = ""
    zenoh: ZenohSettings = msgspec.field(default_factory=ZenohSettings)
    services: Annotated[dict[str, ServiceSpec], msgspec.Meta(min_length=1)]

    def __post_init__(self) -> None:
        if self.name is not None and not NAME_RE.match(self.name):
            raise ValueError("name: use letters, digits, '_', '-' and '.', starting with a letter or digit")
        msgspec.structs.force_setattr(self, "namespace", _check_namespace(self.namespace))


def _check_namespace(namespace: str) -> str:
    """``namespace`` normalised, or a ``ValueError`` that names the field."""
    with blaming("namespace"):
        return normalise_namespace(namespace)


# Compose's short forms, read into the records' forms before validation. Each reader takes the value as YAML
# gives it and returns it as the record's field takes it, or raises ValueError saying what is wrong; a value
# it does not know (a number for a list) passes unchanged, for validation to name.


def _command_words(value: Any) -> Any:
    """``command: python -m x`` is split as a shell would; each word of a list is text (``3``, ``true``)."""
    if isinstance(value, str):
        value = shlex.split(value)
    if isinstance(value, list):
        return [as_text(word) for word in value]
    return value


def _environment_map(value: Any) -> Any:
    """``[KEY=value, KEY]`` or ``{KEY: value}``: values as text, a bare ``KEY`` (or ``KEY: null``) passed through
    from the launcher's environment."""
    if isinstance(value, list):
        pairs: dict[str, str | None] = {}
        for item in value:
            key, sep, text = as_text(item).partition("=")
            pairs[key] = text if sep else None
        return pairs
    if isinstance(value, dict):
        return {str(key): None if text is None else as_text(text) for key, text in value.items()}
    return value


def _depends_on_map(value: Any) -> Any:
    """``[router, map]`` or ``{router: {condition: ...}}``; a name with no settings waits for the start."""
    if isinstance(value, list):
        return {as_text(name): {} for name in value}
    if isinstance(value, dict):
        return {name: {} if spec is None else spec for name, spec in value.items()}
    return value


def _test_words(value: Any) -> Any:
    """A healthcheck's ``test`` as one string (run by a shell) or a list of words, each as text."""
    if isinstance(value, list):
        return [as_text(word) for word in value]
    return value


def _optional_duration(value: Any) -> float | None:
    return None if value is None else parse_duration(value)


#: A key's reader, or the readers of a mapping's keys (a healthcheck's).
_Readers = Mapping[str, "Callable[[Any], Any] | _Readers"]

_HEALTHCHECK_FORMS: _Readers = {
    "test": _test_words,
    "interval": parse_duration,
    "timeout": _optional_duration,
    "start_period": parse_duration,
}
#: In the fields' order, so that problems are listed as the record declares them.
_SERVICE_FORMS: _Readers = {
    "command": _command_words,
    "environment": _environment_map,
    "depends_on": _depends_on_map,
    "restart": parse_restart_policy,
    "healthcheck": _HEALTHCHECK_FORMS,
    "stop_grace_period": parse_duration,
}


def _without_extensions(data: dict[Any, Any]) -> dict[Any, Any]:
    """``data`` less its ``x-`` keys (Compose's extensions: anchors to merge, the launcher's ``x-compose``)."""
    return {key: value for key, value in data.items() if not (isinstance(key, str) and key.startswith("x-"))}


def _read_forms(data: dict[Any, Any], readers: _Readers, place: str, problems: list[str]) -> dict[Any, Any]:
    """``data`` with each key ``readers`` names read; a value that cannot be read adds ``place.key: reason``
    to ``problems`` and is left as written."""
    out = dict(data)
    for key, reader in readers.items():
        if key not in out:
            continue
        if isinstance(reader, Mapping):
            if isinstance(out[key], dict):
                out[key] = _read_forms(out[key], reader, f"{place}.{key}", problems)
            continue
        try:
            out[key] = reader(out[key])
        except ValueError as exc:
            problems.append(f"{place}.{key}: {exc}")
    return out


def validate_stack_file(document: Mapping[str, Any], source: str | Path) -> StackFile:
    """A stack file's (interpolated) document as a :class:`StackFile`: extensions dropped, Compose's short
    forms read, then validated. Raises :class:`ConfigError` naming every short form that cannot be read (all
    services'), else the problems validation finds (:func:`shared.structs.validate`), each as
    ``source: services.NAME.KEY: reason``."""
    problems: list[str] = []
    data = _without_extensions(dict(document))
    services = data.get("services")
    if isinstance(services, dict):
        data["services"] = {
            name: _read_forms(_without_extensions(spec), _SERVICE_FORMS, f"services.{name}", problems)
            if isinstance(spec, dict)
            else spec
            for name, spec in services.items()
        }
    if problems:
        raise ConfigError("\n".join(f"{source}: {problem}" for problem in problems))
    return validate(StackFile, data, source)


def join_namespace(stack_namespace: str, service_namespace: str | None) -> str:
    """A service's namespace is relative to the stack's unless it starts with ``/``."""
    if service_namespace is None:
        return normalise_namespace(stack_namespace)
    if service_namespace.startswith("/"):
        return normalise_namespace(service_namespace)
    return normalise_namespace(f"{stack_namespace}/{service_namespace}")


@dataclass(frozen=True)
class Stack:
    """A validated, interpolated stack file, ready to plan a launch from."""

    source: Path
    project_name: str
    namespace: str
    connect: tuple[str, ...]
    services: Mapping[str, ServiceLaunch]
    #: The Zenoh json5 file of the launcher's own session (``zenoh.config``), if any.
    zenoh_config: str | None = None
    #: The variables interpolation used (shell environment over ``.env``), for ``KEY:`` pass-throughs.
    variables: Mapping[str, str] = field(default_factory=dict, repr=False)

    @property
    def profiles(self) -> list[str]:
        return sorted({profile for spec in self.services.values() for profile in spec.profiles})

    def dependencies(self) -> dict[str, list[str]]:
        return {name: list(spec.depends_on) for name, spec in self.services.items()}

    def select(self, names: Iterable[str] = (), profiles: Iterable[str] = ()) -> list[str]:
        """The services ``up`` starts, in dependency order.

        Named services are started whatever their profiles; without names, every service with no profile
        or an active one. Dependencies are pulled in either way.
        """
        wanted = list(names)
        unknown = [name for name in wanted if name not in self.services]
        if unknown:
            raise ConfigError(f"{self.source}: {no_such('service', unknown, self.services)}")
        active = set(profiles)
        if not wanted:
            wanted = [
                name
                for name, spec in self.services.items()
                if not spec.profiles or active.intersection(spec.profiles)
            ]
        selected = with_dependencies(wanted, self.dependencies())
        return [name for name in dependency_order(self.dependencies()) if name in selected]

    def to_dict(self) -> dict[str, Any]:
        """The normalised stack, as ``zendock config`` prints it."""
        services: dict[str, Any] = {}
        for name, spec in self.services.items():
            entry: dict[str, Any] = {"command": list(spec.command)}
            if spec.working_dir is not None:
                entry["working_dir"] = spec.working_dir
            if spec.namespace is not None:
                entry["namespace"] = spec.namespace
            if spec.environment:
                entry["environment"] = dict(spec.environment)
            if spec.depends_on:
                entry["depends_on"] = {dep: {"condition": d.condition} for dep, d in spec.depends_on.items()}
            entry["restart"] = str(spec.restart)
            if spec.healthcheck is not None:
                entry["healthcheck"] = _healthcheck_dict(spec.healthcheck)
            if spec.profiles:
                entry["profiles"] = list(spec.profiles)
            entry["stop_grace_period"] = format_duration(spec.stop_grace_period)
            services[name] = entry
        return {
            "name": self.project_name,
            "namespace": self.namespace,
            "zenoh": {
                "connect": list(self.connect),
                **({"config": self.zenoh_config} if self.zenoh_config else {}),
            },
            "services": services,
        }


def _healthcheck_dict(check: Healthcheck) -> dict[str, Any]:
    out: dict[str, Any] = {}
    if check.disable:
        out["disable"] = True
    if check.liveliness:
        out["liveliness"] = check.liveliness
    if check.test:
        out["test"] = check.test if isinstance(check.test, str) else list(check.test)
        out["interval"] = format_duration(check.interval)
        out["retries"] = check.retries
    if check.timeout is not None:
        out["timeout"] = format_duration(check.timeout)
    if check.start_period:
        out["start_period"] = format_duration(check.start_period)
    return out


def load_variables(project_dir: Path, env: Mapping[str, str] | None, env_file: Path | None) -> dict[str, str]:
    """Interpolation variables: ``env`` (default: the shell's environment) over the ``.env`` file.

    The ``.env`` file is ``env_file`` when given (it must exist), else ``project_dir/.env`` if present.
    """
    base = dict(os.environ if env is None else env)
    path = env_file if env_file is not None else project_dir / ".env"
    if env_file is not None and not env_file.is_file():
        raise ConfigError(f"{env_file}: env file not found")
    if not path.is_file():
        return base
    try:
        dotenv = parse_env_file(path, base)
    except InterpolationError as exc:
        raise ConfigError(str(exc)) from None
    return {**dotenv, **base}


def project_name_from_dir(project_dir: Path) -> str:
    """Compose's rule: the project directory's name, lower-cased, other characters turned into ``_``."""
    name = re.sub(r"[^a-z0-9_.-]", "_", project_dir.resolve().name.lower()).lstrip("._-")
    return name or "zendock"


def read_document(path: Path) -> dict[str, Any]:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read the stack file: {exc.strerror}") from None
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: invalid YAML: {exc}") from None
    if not isinstance(document, dict):
        raise ConfigError(f"{path}: (top level): expected a mapping with a 'services' key")
    return document


def load_stack(
    path: str | Path,
    *,
    env: Mapping[str, str] | None = None,
    env_file: str | Path | None = None,
    project_dir: str | Path | None = None,
    project_name: str | None = None,
    compose: Mapping[str, list[str]] | None = None,
    interpolate: bool = True,
) -> Stack:
    """Read, interpolate and validate a stack file.

    ``compose`` adds groups of services that run as one process, as the file's own ``x-compose`` does
    (:mod:`deploy.launcher.composition`).

    ``env`` replaces the shell environment for interpolation (tests pass a dict); ``project_dir``
    (default: the current directory) is where ``.env`` is looked up and names the project when the file
    has no ``name``. ``interpolate=False`` keeps every ``${VAR}`` as written (``zendock export`` writes them
    into files that another tool interpolates). Raises :class:`ConfigError` listing every problem found.
    """
    source = Path(path)
    directory = Path(project_dir) if project_dir is not None else Path.cwd()
    variables = load_variables(directory, env, Path(env_file) if env_file is not None else None)
    document = read_document(source)
    zenoh_section = document.get("zenoh")
    if zenoh_section is None:
        document["zenoh"] = {"connect": [DEFAULT_CONNECT]}
    elif isinstance(zenoh_section, dict) and "connect" not in zenoh_section:
        document["zenoh"] = {**zenoh_section, "connect": [DEFAULT_CONNECT]}
    try:
        document = expand_robots(document)
    except RobotTemplateError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    try:
        if interpolate:
            document = interpolate_tree(document, variables)  # type: ignore[assignment]
    except InterpolationError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    declared = document.get("x-compose")
    if declared is not None and not isinstance(declared, dict):
        raise ConfigError(f"{source}: x-compose: expected a mapping of group names to lists of services")
    parsed = validate_stack_file(document, source)
    stack = Stack(
        source=source,
        project_name=project_name or parsed.name or project_name_from_dir(directory),
        namespace=parsed.namespace,
        connect=tuple(parsed.zenoh.connect),
        services={name: spec.launch() for name, spec in parsed.services.items()},
        zenoh_config=parsed.zenoh.config or None,
        variables=variables,
    )
    groups = {**(declared or {}), **(compose or {})}
    if groups:
        try:
            stack = replace(stack, services=compose_groups(stack.services, groups))
        except CompositionError as exc:
            raise ConfigError(f"{source}: {exc}") from None
    check_stack(stack)
    return stack


def check_stack(stack: Stack) -> None:
    """Refuse a stack whose names, dependencies or namespaces do not hold together, naming every problem
    (a stack file's, or one a runner built in Python)."""
    problems = _reference_problems(stack)
    if problems:
        raise ConfigError("\n".join(f"{stack.source}: {problem}" for problem in problems))


def _reference_problems(parsed: Stack) -> list[str]:
    problems = []
    for name, spec in parsed.services.items():
        if not NAME_RE.match(name):
            problems.append(f"services.{name}: a service name uses letters, digits, '_', '-' and '.'")
        for dependency, condition in spec.depends_on.items():
            where = f"services.{name}.depends_on.{dependency}"
            target = parsed.services.get(dependency)
            if target is None:
                problems.append(f"{where}: unknown service")
            elif dependency == name:
                problems.append(f"{where}: a service cannot depend on itself")
            elif condition.condition == "service_healthy" and not (
                target.healthcheck is not None and target.healthcheck.enabled
            ):
                problems.append(f"{where}.condition: service_healthy needs a healthcheck on {dependency}")
        if spec.namespace is not None:
            try:
                join_namespace(parsed.namespace, spec.namespace)
            except ValueError as exc:
                problems.append(f"services.{name}.namespace: {exc}")
    cycle = find_cycle(
        {name: [d for d in spec.depends_on if d != name] for name, spec in parsed.services.items()}
    )
    if cycle:
        problems.append(f"services: dependency cycle: {' -> '.join(cycle)}")
    return problems
