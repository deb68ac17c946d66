"""From a validated stack to what the supervisor runs: argv, environment, directory and checks per service.

This is where launch-time overrides apply (namespace, connect endpoints, extra environment), so tests can
bring the same stack file up on a free port in a fresh namespace.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import deploy
from deploy.launcher.launch import Healthcheck, ServiceLaunch, run_words, standby_words
from deploy.launcher.restart import RestartPolicy
from deploy.launcher.stack_file import (
    DEFAULT_CHECK_TIMEOUT_S,
    DEFAULT_LIVELINESS_TIMEOUT_S,
    Stack,
    join_namespace,
)
from shared.names import node_token_key, normalise_namespace

#: The directory holding the ``shared``, ``services`` and ``deploy`` packages of this zendock.
ZENDOCK_ROOT = Path(deploy.__file__).resolve().parent.parent


def resolve_argv(command: Sequence[str]) -> list[str]:
    """``python`` is this interpreter and ``zendock`` this zendock, so a stack runs from an unactivated venv."""
    head, *rest = command
    if head == "python":
        return [sys.executable, *rest]
    if head == "zendock":
        return [sys.executable, "-m", "deploy.cli", *rest]
    return list(command)


def health_test_argv(test: Sequence[str] | str) -> list[str]:
    """Compose's forms: ``"cmd text"`` and ``[CMD-SHELL, text]`` run in a shell, ``[CMD, ...]`` directly."""
    if isinstance(test, str):
        return ["/bin/sh", "-c", test]
    if test and test[0] == "CMD-SHELL":
        return ["/bin/sh", "-c", " ".join(test[1:])]
    if test and test[0] == "CMD":
        return resolve_argv(test[1:])
    return resolve_argv(test)


@dataclass(frozen=True)
class HealthPlan:
    liveliness_key: str | None
    liveliness_timeout_s: float
    test_argv: tuple[str, ...] | None
    interval_s: float
    test_timeout_s: float
    retries: int
    start_period_s: float


@dataclass(frozen=True)
class ServicePlan:
    name: str
    argv: tuple[str, ...]
    cwd: Path
    env: Mapping[str, str] = field(repr=False)
    namespace: str
    restart: RestartPolicy
    health: HealthPlan | None
    stop_grace_s: float
    #: dependency name -> condition (service_started | service_healthy | service_completed_successfully)
    depends_on: Mapping[str, str]
    #: For a composed group (``zendock container``): the services its one process runs.
    members: tuple[str, ...] = ()
    #: A warm standby's argv (:mod:`deploy.standby`), for a supervisor that keeps one: None where a
    #: standby cannot stand in (a group, another program, another interpreter).
    standby_argv: tuple[str, ...] | None = None


@dataclass(frozen=True)
class LaunchPlan:
    project: str
    namespace: str
    connect: tuple[str, ...]
    services: Mapping[str, ServicePlan]
    #: The Zenoh json5 file of the launcher's own session (absolute), from the stack's ``zenoh.config``.
    zenoh_config: str | None = None
    #: Keep a warm standby of each restartable zendock service (:mod:`deploy.standby`): a restart starts
    #: from it, its imports done, at the cost of a second process's memory per service.
    standby: bool = False

    @property
    def liveliness_needed(self) -> bool:
        return any(p.health is not None and p.health.liveliness_key for p in self.services.values())


def _health_plan(service: str, namespace: str, check: Healthcheck | None) -> HealthPlan | None:
    if check is None or not check.enabled:
        return None
    node_name = check.liveliness if isinstance(check.liveliness, str) else service
    return HealthPlan(
        liveliness_key=node_token_key(namespace, node_name) if check.liveliness else None,
        liveliness_timeout_s=check.timeout if check.timeout is not None else DEFAULT_LIVELINESS_TIMEOUT_S,
        test_argv=tuple(health_test_argv(check.test)) if check.test else None,
        interval_s=max(check.interval, 0.05),
        test_timeout_s=check.timeout if check.timeout is not None else DEFAULT_CHECK_TIMEOUT_S,
        retries=check.retries,
        start_period_s=check.start_period,
    )


def service_environment(
    spec: ServiceLaunch,
    *,
    base: Mapping[str, str],
    namespace: str,
    connect: Sequence[str],
    overrides: Mapping[str, str],
    variables: Mapping[str, str],
) -> dict[str, str]:
    """``base`` (the launcher's environment), then the overrides, the zendock variables, and the service's own.

    ``ZENDOCK_NAMESPACE`` and ``ZENDOCK_CONNECT`` are the defaults every zendock service reads;
    ``PYTHONPATH`` gains this zendock's root so ``python -m services.<name>`` works from any directory.
    A service ``environment`` key without a value passes the variable through from ``variables``.
    """
    env = dict(base)
    env.update(overrides)
    env["ZENDOCK_NAMESPACE"] = namespace
    env["ZENDOCK_CONNECT"] = ",".join(connect)
    env["PYTHONUNBUFFERED"] = "1"
    paths = [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    if str(ZENDOCK_ROOT) not in paths:
        env["PYTHONPATH"] = os.pathsep.join([str(ZENDOCK_ROOT), *paths])
    for key, value in spec.environment.items():
        if value is not None:
            env[key] = value
        elif key in variables:
            env[key] = variables[key]
    return env


def plan_launch(
    stack: Stack,
    *,
    working_dir: str | Path | None = None,
    namespace: str | None = None,
    connect: Sequence[str] | None = None,
    environment: Mapping[str, str] | None = None,
    base_environment: Mapping[str, str] | None = None,
    standby: bool = False,
) -> LaunchPlan:
    """Resolve every service of ``stack``. ``working_dir`` (default: the current directory) is where
    services run and what relative ``working_dir`` keys are resolved against."""
    root = Path(working_dir).resolve() if working_dir is not None else Path.cwd()
    stack_namespace = normalise_namespace(namespace) if namespace is not None else stack.namespace
    endpoints = tuple(connect) if connect else stack.connect
    base = dict(os.environ if base_environment is None else base_environment)
    services = {}
    for name, spec in stack.services.items():
        standby_run = standby_words(spec.run)
        service_namespace = join_namespace(stack_namespace, spec.namespace)
        cwd = (root / spec.working_dir).resolve() if spec.working_dir else root
        services[name] = ServicePlan(
            name=name,
            argv=tuple(resolve_argv(run_words(spec.run))),
            cwd=cwd,
            env=service_environment(
                spec,
                base=base,
                namespace=service_namespace,
                connect=endpoints,
                overrides=environment or {},
                variables=stack.variables,
            ),
            namespace=service_namespace,
            restart=spec.restart,
            health=_health_plan(name, service_namespace, spec.healthcheck),
            stop_grace_s=spec.stop_grace_period,
            depends_on={dep: d.condition for dep, d in spec.depends_on.items()},
            members=spec.members,
            standby_argv=tuple(resolve_argv(standby_run)) if standby_run else None,
        )
    zenoh_config = str((root / stack.zenoh_config).resolve()) if stack.zenoh_config else None
    return LaunchPlan(
        project=stack.project_name,
        namespace=stack_namespace,
        connect=endpoints,
        services=services,
        zenoh_config=zenoh_config,
        standby=standby,
    )


def plan_to_json(plan: LaunchPlan) -> str:
    """The plan as JSON, for the detached supervisor (``zendock up -d``): it runs what ``up`` planned."""
    return json.dumps(
        {
            "project": plan.project,
            "namespace": plan.namespace,
            "connect": list(plan.connect),
            "zenoh_config": plan.zenoh_config,
            "standby": plan.standby,
            "services": [
                {
                    "name": s.name,
                    "argv": list(s.argv),
                    "cwd": str(s.cwd),
                    "env": dict(s.env),
                    "namespace": s.namespace,
                    "restart": {"mode": s.restart.mode, "max_retries": s.restart.max_retries},
                    "health": None if s.health is None else asdict(s.health),
                    "stop_grace_s": s.stop_grace_s,
                    "depends_on": dict(s.depends_on),
                    "members": list(s.members),
                    "standby_argv": None if s.standby_argv is None else list(s.standby_argv),
                }
                for s in plan.services.values()
            ],
        }
    )


def plan_from_json(text: str) -> LaunchPlan:
    """The plan :func:`plan_to_json` wrote; a :class:`ValueError` when the text is not one."""
    try:
        data = json.loads(text)
        services = {
            s["name"]: ServicePlan(
                name=s["name"],
                argv=tuple(s["argv"]),
                cwd=Path(s["cwd"]),
                env=dict(s["env"]),
                namespace=s["namespace"],
                restart=RestartPolicy(s["restart"]["mode"], s["restart"]["max_retries"]),
                health=None
                if s["health"] is None
                else HealthPlan(**{**s["health"], "test_argv": _optional_tuple(s["health"]["test_argv"])}),
                stop_grace_s=float(s["stop_grace_s"]),
                depends_on=dict(s["depends_on"]),
                members=tuple(s["members"]),
                standby_argv=_optional_tuple(s["standby_argv"]),
            )
            for s in data["services"]
        }
        return LaunchPlan(
            project=data["project"],
            namespace=data["namespace"],
            connect=tuple(data["connect"]),
            services=services,
            zenoh_config=data["zenoh_config"],
            standby=bool(data["standby"]),
        )
    except (ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"not a launch plan: {exc}") from None


def _optional_tuple(words: list[str] | None) -> tuple[str, ...] | None:
    return None if words is None else tuple(words)
