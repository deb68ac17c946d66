"""A stack file as a Compose file: the router and each service in a container of its own.

The stack file is the one description of the deployment; ``deploy/docker-compose.yml`` (and its secure
overlay) are generated from it, as honcho's ``export/`` writes systemd units from a Procfile, and a test
compares generated with committed. Pure: a :class:`~deploy.launcher.stack_file.Stack` loaded without
interpolation in, YAML text out (Compose interpolates the same ``${VAR:-default}`` forms when it runs).

What changes on the way into containers, each rule once, here:

- every service runs from one image on a user-defined bridge network, so each is its own network host and
  reaches the others only through the router, as on several machines (``init`` reaps zombies and forwards
  SIGTERM even with a shell in between);
- the router (the service whose command is ``zendock router``) is built here, listens on every interface of
  its container, publishes its port on the host's loopback unless ``ZENOH_PUBLISH_ADDR`` says otherwise, and
  is healthy when its port accepts a connection;
- the other services connect to the router by its container name and are healthy when the router sees
  their node's liveliness token (``zendock health``, as ``zendock up`` checks liveliness);
- host paths under ``.zendock/`` become named volumes, and variables that name host paths or host-only
  settings are read as unset (their defaults);
- the live view serves on every interface, its port published on loopback.
- secure overlay: each service's ``--zenoh-config FILE`` becomes ``ZENDOCK_ZENOH_CONFIG`` (the health check
  reads it too), without TLS (that needs certificates mounted: see deploy/zenoh/secure/README.md).
"""

from __future__ import annotations

import re
from typing import Any

import yaml

from deploy.launcher.durations import format_duration
from deploy.launcher.launch import Healthcheck, ModuleRun, ProgramRun, ServiceLaunch
from deploy.launcher.stack_file import Stack
from shared.interpolation import interpolate

IMAGE = "zendock:latest"
NETWORK = "bus"
ROUTER_PORT = 7447
#: Where the services find the router: its container name on the bus network.
CONNECT = f"${{ZENOH_CONNECT:-tcp/router:{ROUTER_PORT}}}"
BUILD = {
    "context": "..",
    "dockerfile": "deploy/docker/Dockerfile",
    "args": {"BASE": "${ZENDOCK_BASE_IMAGE:-python:3.11-slim-bookworm}"},
}
ROUTER_PORTS = [f"${{ZENOH_PUBLISH_ADDR:-127.0.0.1}}:${{ZENOH_PUBLISH_PORT:-{ROUTER_PORT}}}:{ROUTER_PORT}"]
ROUTER_TEST = [
    "CMD",
    "python3",
    "-c",
    f"import socket; socket.create_connection(('127.0.0.1', {ROUTER_PORT}), 2).close()",
]
#: A container health check every 10 s; a service has a minute to start (imports, first map), the router 10 s.
HEALTH = {"interval": "10s", "timeout": "8s", "retries": 3, "start_period": "60s"}
ROUTER_START_PERIOD = "10s"
#: Variables with no meaning in a container, read as unset: the host's router endpoint, a host path, TLS
#: (certificates are not mounted).
HOST_ONLY_VARIABLES = ("ZENOH_LISTEN", "ZENDOCK_GLASS_MEMORY", "ZENDOCK_TLS")
#: Host paths under .zendock/ and the named volume each becomes (first match wins).
VOLUMES = ((".zendock/maps/", "maps", "/maps/"), (".zendock/", "state", "/state/"))
#: Services that serve the host: arguments to serve on every interface, and the port published on loopback.
#: zendock services that serve outside the network: the flags that open them, the ports published.
SERVED = {"viz": (["--host", "0.0.0.0"], ["127.0.0.1:8765:8765"])}
ZENOH_CONFIG_FLAG = "--zenoh-config"

_HOST_ONLY_RE = re.compile(r"\$\{(?:" + "|".join(HOST_ONLY_VARIABLES) + r")[-+:?][^${}]*\}")


def _without_host_variables(word: str) -> str:
    """``${ZENDOCK_GLASS_MEMORY:-.zendock/x}`` becomes ``.zendock/x``: the expression read with the variable unset."""
    return _HOST_ONLY_RE.sub(lambda match: interpolate(match.group(0), {}), word)


def _in_volumes(word: str, volumes: list[str]) -> str:
    for host, volume, mount in VOLUMES:
        if host in word:
            mount_spec = f"{volume}:{mount.rstrip('/')}"
            if mount_spec not in volumes:
                volumes.append(mount_spec)
            return word.replace(host, mount)
    return word


def is_router(spec: ServiceLaunch) -> bool:
    return isinstance(spec.run, ProgramRun) and list(spec.run.words[:2]) == ["zendock", "router"]


def _router_command(command: list[str]) -> list[str]:
    """The stack's router command, listening on every interface of its container."""
    words = [_without_host_variables(word) for word in command]
    if "--listen" in words:
        at = words.index("--listen")
        del words[at : at + 2]
    return [*words, "--listen", f"tcp/0.0.0.0:{ROUTER_PORT}"]


def _split_zenoh_config(command: list[str]) -> tuple[list[str], str | None]:
    if ZENOH_CONFIG_FLAG not in command:
        return list(command), None
    at = command.index(ZENOH_CONFIG_FLAG)
    return [*command[:at], *command[at + 2 :]], command[at + 1]


def _healthcheck(name: str, check: Healthcheck | None) -> dict[str, Any] | None:
    if check is None or not check.enabled:
        return None
    if check.test:
        test = ["CMD-SHELL", check.test] if isinstance(check.test, str) else ["CMD", *check.test]
    else:
        node = check.liveliness if isinstance(check.liveliness, str) else name
        test = ["CMD", "zendock", "health", "-q", node]
    return {"test": test, **HEALTH}


def _service(name: str, spec: ServiceLaunch, namespace: str, volumes: list[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    router = is_router(spec)
    if router:
        out["build"] = BUILD
    out["image"] = IMAGE
    out["init"] = True
    command, _ = _split_zenoh_config(list(spec.command))
    if router:
        command = _router_command(command)
    else:
        command = [_in_volumes(_without_host_variables(word), volumes) for word in command]
    served = SERVED.get(spec.run.service) if isinstance(spec.run, ModuleRun) else None
    if served is not None:
        command = [*command[:3], *served[0], *command[3:]]
    out["command"] = command
    if not router:
        out["environment"] = {
            "ZENDOCK_CONNECT": CONNECT,
            "ZENDOCK_NAMESPACE": f"${{ZENDOCK_NAMESPACE:-{namespace}}}",
            **{key: value for key, value in spec.environment.items()},
        }
    if spec.depends_on:
        out["depends_on"] = {dep: {"condition": d.condition} for dep, d in spec.depends_on.items()}
    out["restart"] = str(spec.restart)
    out["stop_grace_period"] = format_duration(spec.stop_grace_period)
    out["networks"] = [NETWORK]
    ports = ROUTER_PORTS if router else served[1] if served is not None else None
    if ports:
        out["ports"] = list(ports)
    if volumes:
        out["volumes"] = volumes
    if router:
        out["healthcheck"] = {"test": ROUTER_TEST, **HEALTH, "start_period": ROUTER_START_PERIOD}
    else:
        check = _healthcheck(name, spec.healthcheck)
        if check is not None:
            out["healthcheck"] = check
    if spec.profiles:
        out["profiles"] = list(spec.profiles)
    return out


def runs_on_host_only(spec: ServiceLaunch) -> bool:
    """A service whose interpreter is a host virtualenv's (``.venv-ros2/bin/python``: the ROS 2 DDS face, on
    rclpy wheels the image does not carry) has no container: the Compose files leave it out."""
    return isinstance(spec.run, ModuleRun) and spec.run.python.startswith(".venv")


def compose_document(stack: Stack) -> dict[str, Any]:
    """The Compose file's content for ``stack`` (loaded with ``interpolate=False``), without the services that
    run on the host only (:func:`runs_on_host_only`)."""
    volumes: list[str] = []
    services = {}
    for name, spec in stack.services.items():
        if runs_on_host_only(spec):
            continue
        own: list[str] = []
        services[name] = _service(name, spec, stack.namespace, own)
        volumes.extend(volume for volume in own if volume not in volumes)
    document: dict[str, Any] = {
        "name": stack.project_name,
        "services": services,
        "networks": {NETWORK: {"driver": "bridge"}},
    }
    if volumes:
        document["volumes"] = {volume.split(":", 1)[0]: {} for volume in volumes}
    return document


def secure_overlay_document(stack: Stack) -> dict[str, Any]:
    """The overlay for a secure stack: the router's ``--config``, each service's own Zenoh user."""
    services: dict[str, Any] = {}
    for name, spec in stack.services.items():
        command, config = _split_zenoh_config(list(spec.command))
        if is_router(spec):
            services[name] = {"command": _router_command(command)}
        elif config is not None:
            services[name] = {"environment": {"ZENDOCK_ZENOH_CONFIG": _without_host_variables(config)}}
    return {"services": services}


def render(document: dict[str, Any], header: str) -> str:
    """YAML with flow-style leaves, a blank line between top-level sections and between services."""
    lines: list[str] = []
    for line in yaml.safe_dump(document, sort_keys=False, default_flow_style=None, width=100).splitlines():
        top_level = not line.startswith(" ")
        service = re.fullmatch(r"  [A-Za-z0-9_.-]+:", line) is not None and not lines[-1].endswith(":")
        if top_level or service:
            lines.append("")
        lines.append(line)
    return "".join(f"# {line}".rstrip() + "\n" for line in header.splitlines()) + "\n".join(lines) + "\n"


def compose_header(source: str, output: str | None) -> str:
    compose = output or "docker-compose.yml"
    written = f" -o {output}" if output else ""
    return f"""\
zendock in containers: the router and each service in a container of its own, on a user-defined bridge
network, so every service is its own network host and reaches the others only through the router, as on
several machines. One image (deploy/docker/Dockerfile).

Generated from {source}: change the stack file, not this one, and regenerate with
  zendock export compose -f {source}{written}
(tests/unit/test_docker_compose.py checks that the committed file is current).

  {f"podman-compose -f {compose} up -d":<56} (or docker compose; `make test-containers` runs it)
  {"zendock dock --connect tcp/127.0.0.1:7447":<56} (from the host, through the published port)

ZENDOCK_BASE_IMAGE builds on another base (deploy/docker/base-image.sh makes a registry-free one). Only the
router's port is published, on the host's loopback unless ZENOH_PUBLISH_ADDR says otherwise; across hosts,
run the router where every host reaches it and set ZENOH_CONNECT to it on the others.
"""


def secure_header(source: str, output: str | None) -> str:
    overlay = output or "docker-compose.secure.yml"
    written = f" -o {output}" if output else ""
    return f"""\
The secure profile in containers, layered on the default compose file:
  podman-compose -f deploy/docker-compose.yml -f {overlay} up -d
The router authenticates every client and enforces deploy/zenoh/secure's access-control list; each service
connects as its own user (ZENDOCK_ZENOH_CONFIG names the user's file, which its health check uses too).
From the host: zendock dock --connect tcp/127.0.0.1:7447 --zenoh-config deploy/zenoh/secure/operator.json5.
Development passwords: replace them as deploy/zenoh/secure/README.md says before any real deployment.

Generated from {source}: change the stack file, not this one, and regenerate with
  zendock export compose --secure -f {source}{written}
(tests/unit/test_docker_compose.py checks that the committed file is current).
"""
