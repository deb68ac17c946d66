"""``zendock container``: several services in one process, like a ROS 2 component container.

Usage::

    zendock container [--namespace NS] [--connect E]... [--log-level L] SERVICE [ARGS...] [+ SERVICE [ARGS...]]...

    zendock container --namespace r0 battery -p use_sim_time=true + pose -p use_sim_time=true \\
        + planner -p use_sim_time=true -p map_yaml=maps/map.yaml + docking -p use_sim_time=true -p dock_database=W

Each SERVICE takes exactly the flags and parameters of ``python -m services.SERVICE``; the group's
``--namespace``, ``--connect``, ``--zenoh-config`` and ``--log-level`` are given to every one of them (or come,
as for a service alone, from ZENDOCK_NAMESPACE and ZENDOCK_CONNECT). The services share one Zenoh session:
messages between them stay in the process (see :mod:`shared.composition`). A service is loaded by name
(``services.<SERVICE>.node`` and its ``SERVICE`` spec), as a component container loads its plugins.
Exit codes: 0 stopped by a signal, 1 a node stopped on its own, 2 bad input.
"""

from __future__ import annotations

import argparse
import importlib

from shared.composition import Member, serve_group
from shared.config_errors import ConfigError
from shared.runtime import ServiceSpec

SEPARATOR = "+"


def split_members(words: list[str]) -> list[list[str]]:
    """``["battery", "-p", "a=1", "+", "pose"]`` -> ``[["battery", "-p", "a=1"], ["pose"]]``."""
    groups: list[list[str]] = [[]]
    for word in words:
        if word == SEPARATOR:
            groups.append([])
        else:
            groups[-1].append(word)
    if any(not g for g in groups):
        raise ConfigError(
            f"each '{SEPARATOR}' must separate two services: SERVICE [ARGS...] {SEPARATOR} SERVICE ..."
        )
    return groups


def load_spec(name: str) -> ServiceSpec:
    if not name.isidentifier():
        raise ConfigError(f"{name!r} is not a service name")
    try:
        module = importlib.import_module(f"services.{name}.node")
    except ModuleNotFoundError as exc:
        raise ConfigError(f"no service {name!r} (services.{name}.node: {exc})") from None
    spec = getattr(module, "SERVICE", None)
    if not isinstance(spec, ServiceSpec):
        raise ConfigError(f"services.{name}.node has no SERVICE spec: it cannot run in a container")
    return spec


def members_from(args: argparse.Namespace) -> list[Member]:
    if not args.services:
        raise ConfigError("name at least one service: SERVICE [ARGS...] [+ SERVICE [ARGS...]]...")
    shared_flags: list[str] = []
    if args.namespace is not None:
        shared_flags += ["--namespace", args.namespace]
    for endpoint in args.connect or []:
        shared_flags += ["--connect", endpoint]
    if args.zenoh_config:
        shared_flags += ["--zenoh-config", args.zenoh_config]
    if args.log_level:
        shared_flags += ["--log-level", args.log_level]
    members = []
    names: set[str] = set()
    for words in split_members(args.services):
        spec = load_spec(words[0])
        options, params = spec.parse([*words[1:], *shared_flags])
        if options.node_name in names:
            raise ConfigError(f"two services named {options.node_name!r} in one group (use --node-name)")
        names.add(options.node_name)
        members.append(Member(spec, options, params))
    first = members[0].options
    for member in members[1:]:
        if (member.options.connect, member.options.listen, member.options.zenoh_config) != (
            first.connect,
            first.listen,
            first.zenoh_config,
        ):
            raise ConfigError(
                f"{member.label}: every service of a group shares one session: give --connect, "
                "--listen and --zenoh-config to the group, not to one service"
            )
    return members


def _run(args: argparse.Namespace) -> int:
    return serve_group(members_from(args))  # a ConfigError: one line and exit 2, from deploy.cli


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "container",
        help="several services in one process on one session (a component container)",
        description="Run services together: SERVICE [ARGS...] + SERVICE [ARGS...] ...; each takes the flags of "
        "python -m services.SERVICE.",
    )
    p.add_argument("--namespace", default=None, help="every service's namespace")
    p.add_argument(
        "--connect", action="append", default=None, metavar="ENDPOINT", help="Zenoh endpoint (repeatable)"
    )
    p.add_argument("--zenoh-config", default=None, metavar="FILE", help="Zenoh json5 configuration file")
    p.add_argument(
        "--log-level", default=None, type=str.upper, choices=["DEBUG", "INFO", "WARNING", "ERROR", "CRITICAL"]
    )
    p.add_argument("services", nargs=argparse.REMAINDER, metavar="SERVICE [ARGS...] [+ SERVICE ...]")
    p.set_defaults(func=_run)
