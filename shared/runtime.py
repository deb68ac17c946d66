"""The common shell of every service: flags, parameters, logging, the session, signals.

Every ``python -m services.<name>`` takes the same flags::

    --namespace NS          robot namespace (env ZENDOCK_NAMESPACE)
    --connect ENDPOINT      repeatable; default tcp/127.0.0.1:7447 (env ZENDOCK_CONNECT, else ZENOH_CONNECT)
    --listen ENDPOINT       repeatable
    --zenoh-config FILE     a Zenoh json5 config applied before the flags (env ZENDOCK_ZENOH_CONFIG)
    --config FILE           YAML parameters (flat, or ROS style ``node: {ros__parameters: {...}}``)
    -p NAME=VALUE           repeatable parameter override, value parsed as YAML
    --node-name NAME        default: the service's name
    --log-level LEVEL

Parameters are a record (a msgspec ``Struct``) per service (unknown names and bad values are errors). A service with
several parts nests a model per part, as Nav2 names ``controller.k_phi``; a dotted NAME sets one field
of a part and leaves its other fields as they were::

    -p lidar.noise_m=0.02                   # the simulator's lidar model, field noise_m
    --config sim.yaml                       # lidar: {noise_m: 0.02}  (a nested map; ``lidar.noise_m: 0.02`` also works)

Overrides apply after the file, field by field (``-p lidar.rate_hz=5`` keeps the file's ``lidar.noise_m``).
A dotted name whose part is unknown, or is not a group of parameters, is an error naming the whole
name, as a bad flat name or value is. A bad flag or parameter prints one clear message and exits with code 2. SIGINT and SIGTERM stop the node, close the
session and exit 0. :func:`run_service` is the whole lifecycle; tests call :func:`serve` with options.

While it runs, every service answers ``<ns>/<node>/_param/{list,get,set}`` (:mod:`shared.parameter_server`):
the fields its model marks :func:`~shared.parameters.runtime_settable` change through ``zendock param set``,
validated by the same model; the others are read at start-up only.
"""

from __future__ import annotations

import argparse
import logging
import os
import re
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol, TypeVar

import msgspec
import zenoh

from shared import structs
from shared.bus_env import connect_from_env
from shared.config_errors import CONFIG_ERROR_EXIT, ConfigError
from shared.contracts.enforce import hold_to_contract
from shared.lifecycle_states import serve_lifecycle_states
from shared.names import normalise_namespace
from shared.node import Node
from shared.parameter_server import attach_parameters
from shared.parameters import ServiceParams
from shared.session import DEFAULT_ROUTER_ENDPOINT, SessionSpec, open_session
from shared.waiting import SIGNAL_CHECK_S, wait_interruptibly

P = TypeVar("P", bound="ServiceParams")


def open_session_unless(spec: SessionSpec, stopped: threading.Event) -> zenoh.Session | None:
    """Open a session, or give up (``None``) once ``stopped`` is set: ``zenoh.open`` blocks in native code
    while no router answers, where no signal handler can run, so it opens on a helper thread while the
    main thread keeps waking for signals. A session that opens after the stop is closed at once."""
    result: list[zenoh.Session | BaseException] = []
    done = threading.Event()
    lock = threading.Lock()
    abandoned = False

    def connect() -> None:
        outcome: zenoh.Session | BaseException
        try:
            outcome = open_session(spec)
        except BaseException as exc:  # handed to the main thread, raised there
            outcome = exc
        with lock:
            if abandoned:
                if isinstance(outcome, zenoh.Session):
                    outcome.close()
                return
            result.append(outcome)
            done.set()

    threading.Thread(target=connect, name="zendock-connect", daemon=True).start()
    while not wait_interruptibly(done, SIGNAL_CHECK_S):
        if stopped.is_set():
            with lock:
                if not done.is_set():
                    abandoned = True
                    return None
            break
    outcome = result[0]
    if isinstance(outcome, BaseException):
        raise outcome
    if stopped.is_set():
        outcome.close()
        return None
    return outcome


class Closeable(Protocol):
    def close(self) -> None: ...


class ServiceOptions(msgspec.Struct, frozen=True):
    """Everything a service needs to start, after flags and environment are read."""

    node_name: str
    namespace: str = ""
    connect: tuple[str, ...] = (DEFAULT_ROUTER_ENDPOINT,)
    listen: tuple[str, ...] = ()
    zenoh_config: str | None = None
    config_file: str | None = None
    overrides: dict[str, Any] = msgspec.field(default_factory=dict)
    log_level: str = "INFO"

    def session_spec(self) -> SessionSpec:
        return SessionSpec(
            mode="client", connect=self.connect, listen=self.listen, config_file=self.zenoh_config
        )


def parse_parameter_value(text: str) -> Any:
    """A parameter's VALUE as YAML (``0.5``, ``true``, ``[0.1, 0, 0]``), the one reading of ``-p`` and
    ``zendock param set``; text that is not YAML stays text."""
    plain = _plain_scalar(text)
    if plain is not _NOT_PLAIN:
        return plain
    import yaml  # noqa: PLC0415 - most services are given only plain scalars, and yaml is slow to import

    try:
        return yaml.safe_load(text) if text.strip() else ""
    except yaml.YAMLError:
        return text


_NOT_PLAIN = object()
_PLAIN_INT = re.compile(r"-?(?:0|[1-9][0-9]*)")
_PLAIN_FLOAT = re.compile(r"-?(?:0|[1-9][0-9]*)\.[0-9]+")
_PLAIN_WORD = re.compile(r"[A-Za-z_/][A-Za-z0-9_/.\-]*")
_YAML_WORDS = {"null", "true", "false", "yes", "no", "on", "off", "y", "n"}


def _plain_scalar(text: str) -> Any:
    """``true``, ``false``, ``12``, ``-0.5``, a name or a path, read as YAML reads them, without loading a YAML parser;
    anything else (``yes``, ``1e3``, ``0o7``, lists) goes to YAML."""
    if text in ("true", "false"):
        return text == "true"
    if _PLAIN_INT.fullmatch(text):
        return int(text)
    if _PLAIN_FLOAT.fullmatch(text):
        return float(text)
    if _PLAIN_WORD.fullmatch(text) and text.lower() not in _YAML_WORDS:
        return text  # a name or a path
    return _NOT_PLAIN


def _parse_override(text: str) -> tuple[str, Any]:
    name, sep, raw = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise ConfigError(f"-p {text!r}: expected NAME=VALUE")
    return name, parse_parameter_value(raw)


def _group_model(model: type[msgspec.Struct], name: str) -> type[msgspec.Struct] | None:
    """The record of ``model``'s field ``name`` when that field is a nested group of parameters, else None."""
    spec = structs.field_spec(model, name)
    return spec.group if spec is not None else None


def set_dotted(
    values: dict[str, Any], name: str, value: Any, model: type[msgspec.Struct], source: str
) -> None:
    """Set parameter ``name`` (``field`` or ``group.field``, any depth) to ``value`` in ``values``.

    Each part before the last must name a nested group of ``model``; the last part and the value are left
    to the model's validation (which names them). A mapping value merges into what is already there.
    """
    parts = name.split(".")
    if any(not part.strip() for part in parts):
        raise ConfigError(f"{source}: {name}: not a parameter name (empty part)")
    target, here = values, model
    for depth, part in enumerate(parts[:-1]):
        where = ".".join(parts[: depth + 1])
        if part not in structs.field_names(here):
            known = ", ".join(n for n in structs.field_names(here) if _group_model(here, n)) or "none"
            raise ConfigError(f"{source}: {name}: unknown group {where!r} (groups: {known})")
        group = _group_model(here, part)
        if group is None:
            raise ConfigError(f"{source}: {name}: {where!r} is a single parameter, not a group")
        child = target.get(part)
        if not isinstance(child, dict):
            child = target[part] = {}
        target, here = child, group
    last = parts[-1]
    group = _group_model(here, last)
    if group is not None and isinstance(value, dict) and isinstance(target.get(last), dict):
        for key, item in value.items():  # a map for a group merges into what an earlier source set
            set_dotted(target[last], str(key), item, group, source)
        return
    target[last] = value


def build_arg_parser(service_name: str, description: str = "") -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=f"python -m services.{service_name}", description=description)
    env_connect = list(connect_from_env())
    parser.add_argument(
        "--namespace", default=os.environ.get("ZENDOCK_NAMESPACE", ""), help="robot namespace"
    )
    parser.add_argument(
        "--connect",
        action="append",
        default=None,
        metavar="ENDPOINT",
        help="Zenoh endpoint to connect to (repeatable; env ZENDOCK_CONNECT, else ZENOH_CONNECT; "
        f"default {DEFAULT_ROUTER_ENDPOINT})",
    )
    parser.add_argument(
        "--listen", action="append", default=[], metavar="ENDPOINT", help="Zenoh endpoint to listen on"
    )
    parser.add_argument(
        "--zenoh-config",
        default=os.environ.get("ZENDOCK_ZENOH_CONFIG") or None,
        metavar="FILE",
        help="Zenoh json5 configuration file (env ZENDOCK_ZENOH_CONFIG)",
    )
    parser.add_argument("--config", default=None, metavar="FILE", help="YAML file of parameters")
    parser.add_argument(
        "-p", "--param", action="append", default=[], metavar="NAME=VALUE", help="set a parameter"
    )
    parser.add_argument("--node-name", default=service_name, help="name of the node on the bus")
    parser.add_argument(
        "--log-level",
        default="INFO",
        type=str.upper,
        choices=["DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL"],
    )
    parser.set_defaults(_env_connect=env_connect)
    return parser


def options_from_args(args: argparse.Namespace, flag_params: dict[str, str] | None = None) -> ServiceOptions:
    """Turn parsed flags into :class:`ServiceOptions`; ``flag_params`` maps extra flags to parameters."""
    overrides: dict[str, Any] = {}
    for dest, param in (flag_params or {}).items():
        value = getattr(args, dest, None)
        if value is not None:
            overrides[param] = value
    for text in args.param:
        name, value = _parse_override(text)
        overrides[name] = value
    try:
        namespace = normalise_namespace(args.namespace)
    except ValueError as exc:
        raise ConfigError(f"--namespace: {exc}") from None
    connect = tuple(args.connect or args._env_connect or [DEFAULT_ROUTER_ENDPOINT])
    return ServiceOptions(
        node_name=args.node_name,
        namespace=namespace,
        connect=connect,
        listen=tuple(args.listen),
        zenoh_config=args.zenoh_config,
        config_file=args.config,
        overrides=overrides,
        log_level=args.log_level,
    )


def load_params(model: type[P], options: ServiceOptions) -> P:
    """Parameters from the config file, then ``-p`` overrides, validated by ``model``."""
    values: dict[str, Any] = {}
    source = "parameters"
    if options.config_file:
        path = Path(options.config_file)
        source = str(path)
        import yaml  # noqa: PLC0415 - see parse_parameter_value

        try:
            data = yaml.safe_load(path.read_text()) or {}
        except OSError as exc:
            raise ConfigError(f"{path}: cannot read parameter file: {exc.strerror or exc}") from None
        except yaml.YAMLError as exc:
            raise ConfigError(f"{path}: not valid YAML: {exc}") from None
        if not isinstance(data, dict):
            raise ConfigError(f"{path}: expected a mapping of parameter names to values")
        for scope in (options.node_name, "/**"):
            scoped = data.get(scope)
            if isinstance(scoped, dict) and isinstance(scoped.get("ros__parameters"), dict):
                data = scoped["ros__parameters"]
                break
        for name, value in data.items():
            set_dotted(values, str(name), value, model, source)
    for name, value in options.overrides.items():
        set_dotted(values, name, value, model, "parameters")
    return structs.validate(model, values, source)


def configure_logging(options: ServiceOptions) -> logging.Logger:
    ns = f"{options.namespace}/" if options.namespace else ""
    logging.basicConfig(
        level=options.log_level,
        format=f"%(asctime)s %(levelname)s [{ns}{options.node_name}] %(message)s",
        datefmt="%H:%M:%S",
        stream=sys.stderr,
        force=True,
    )
    return logging.getLogger(options.node_name)


def serve(
    options: ServiceOptions,
    params: P,
    build: Callable[[Node, P], Closeable | None],
    *,
    install_signal_handlers: bool = True,
    service_name: str | None = None,
) -> int:
    """Open the session, build the service on a node, serve its parameters (:mod:`shared.parameter_server`)
    and the Nav2 lifecycle states ``service_name`` (default: the node's name) answers for, announce it,
    spin until stopped, close everything."""
    log = configure_logging(options)
    log.info("connecting to %s", ",".join(options.connect))
    stopped = threading.Event()
    nodes: list[Node] = []

    def stop(*_: object) -> None:
        stopped.set()
        for each in nodes:
            each.shutdown()

    if install_signal_handlers:  # before connecting: SIGTERM while no router answers still ends it with 0
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, stop)
    opened = open_session_unless(options.session_spec(), stopped)
    if opened is None:
        log.info("stopped before the router answered")
        return 0
    with opened as session:
        node = Node(
            options.node_name, session, options.namespace, use_sim_time=params.use_sim_time, logger=log
        )
        nodes.append(node)
        hold_to_contract(node)
        if stopped.is_set():
            node.close()
            return 0
        service = build(node, params)
        parameters = attach_parameters(node, params, service)
        serve_lifecycle_states(node, service_name or node.name)  # held and closed by the node
        node.declare_ready()
        log.info("ready (namespace %r, connect %s)", options.namespace, ",".join(options.connect))
        try:
            node.spin()
        finally:
            parameters.close()
            if service is not None:
                service.close()
            node.close()
    log.info("stopped")
    return 0


class ServiceSpec(msgspec.Struct, frozen=True):
    """What makes a service, apart from running it: its name, parameters and how to build it on a node.

    ``python -m services.<name>`` runs one alone (:meth:`run`); ``zendock container`` runs several in one
    process on one session (:mod:`shared.composition`), each on its own node, from the same spec.
    """

    name: str
    params_model: type[ServiceParams]
    build: Callable[[Node, Any], Closeable | None]
    description: str = ""
    add_flags: Callable[[argparse.ArgumentParser], dict[str, str]] | None = None
    #: Process-wide set-up before the service runs (e.g. allocator tuning for image-sized buffers).
    prepare: Callable[[], None] | None = None

    def parse(self, argv: Sequence[str] | None) -> tuple[ServiceOptions, ServiceParams]:
        """Flags and parameters, validated; :class:`ConfigError` names what is wrong (argparse exits on
        an unknown flag, as it does for the service alone)."""
        parser = build_arg_parser(self.name, self.description)
        flag_params = self.add_flags(parser) if self.add_flags else {}
        args = parser.parse_args(argv)
        options = options_from_args(args, flag_params)
        return options, load_params(self.params_model, options)

    def run(self, argv: Sequence[str] | None = None) -> int:
        """The whole life of ``python -m services.<name>``: parse, validate, serve. Returns the exit code."""
        prog = f"python -m services.{self.name}"
        try:
            options, params = self.parse(argv)
        except ConfigError as exc:
            print(f"{prog}: error: {exc}", file=sys.stderr)
            return CONFIG_ERROR_EXIT
        if self.prepare is not None:
            self.prepare()
        try:
            return serve(options, params, self.build, service_name=self.name)
        except ConfigError as exc:  # raised while building (a bad world file, a bad map)
            print(f"{prog}: error: {exc}", file=sys.stderr)
            return CONFIG_ERROR_EXIT


def run_service(
    service_name: str,
    params_model: type[P],
    build: Callable[[Node, P], Closeable | None],
    argv: Sequence[str] | None = None,
    *,
    description: str = "",
    add_flags: Callable[[argparse.ArgumentParser], dict[str, str]] | None = None,
) -> int:
    """:meth:`ServiceSpec.run` for a service given by its parts.

    ``add_flags`` may add service-specific flags and returns which parameter each one sets
    (e.g. ``--world`` sets ``world``).
    """
    return ServiceSpec(service_name, params_model, build, description, add_flags).run(argv)
