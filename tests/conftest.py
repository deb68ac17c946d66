"""Fixtures shared by every test: a router on a free port, a fresh namespace, service processes."""

from __future__ import annotations

import os
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
import zenoh

from shared.contracts.enforce import STRICT_ENV
from shared.session import SessionSpec, open_session
from tests.support.processes import ServiceProcess, free_port

# Every zendock service this suite starts (they inherit the environment) refuses to declare an endpoint its
# contract does not name: shared/contracts and the services' wiring cannot drift apart unnoticed.
os.environ[STRICT_ENV] = "1"


@pytest.fixture
def router_endpoint() -> Iterator[str]:
    """An in-process Zenoh router listening on a free loopback port."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))):
        yield endpoint


@pytest.fixture
def bus(router_endpoint: str) -> Iterator[zenoh.Session]:
    """A plain Zenoh client session on the test router."""
    with open_session(SessionSpec(mode="client", connect=(router_endpoint,))) as session:
        yield session


@pytest.fixture
def namespace() -> str:
    return f"t{uuid.uuid4().hex[:8]}"


@pytest.fixture
def spawn(router_endpoint: str, namespace: str, tmp_path: Path, request: pytest.FixtureRequest) -> Iterator:
    """``spawn("simulator", "--world", path, ...)`` starts ``python -m services.<name>`` on the test router.

    Every process is stopped (its whole group) when the test ends, pass or fail; a failing test's report
    shows each service's output.
    """
    started: list[ServiceProcess] = []

    def _spawn(service: str, *args: str, namespace_override: str | None = None) -> ServiceProcess:
        ns = namespace if namespace_override is None else namespace_override
        proc = ServiceProcess(
            f"services.{service}",
            ["--connect", router_endpoint, "--namespace", ns, *args],
            tmp_path / f"{service}-{len(started)}.log",
        )
        started.append(proc)
        return proc

    yield _spawn
    failed = getattr(request.node, "rep_call", None) is not None and request.node.rep_call.failed
    for proc in started:
        proc.stop()
        if failed:
            print(f"\n----- output of {proc.module} -----\n{proc.output()[-4000:]}")


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):  # type: ignore[no-untyped-def]
    report = yield
    setattr(item, f"rep_{report.when}", report)
    return report


@pytest.fixture
def launch_stack(tmp_path: Path, namespace: str) -> Iterator:
    """``launch_stack("simulator", "pose", env={...})`` brings services of the default stack up through the
    launcher's API, on an embedded router at a free port, in a fresh namespace, and waits until they are
    healthy. Teardown stops everything, grandchildren included, even when the test fails.
    """
    from deploy.launcher import Launcher, free_endpoint, load_stack
    from tests.support.processes import REPO_ROOT

    launchers: list = []

    def _launch(*services: str, env: dict[str, str] | None = None, healthy_timeout_s: float = 60.0):  # type: ignore[no-untyped-def]
        endpoint = free_endpoint()
        variables = {"ZENOH_LISTEN": endpoint, "ZENOH_CONNECT": endpoint, **(env or {})}
        stack = load_stack(REPO_ROOT / "deploy" / "stack.yaml", env=variables, project_dir=REPO_ROOT)
        launcher = Launcher(
            stack,
            services=("router", *services),
            project_dir=tmp_path / f"stack{len(launchers)}",
            working_dir=REPO_ROOT,
            namespace=namespace,
            project_name=f"test{len(launchers)}",
        )
        launchers.append(launcher)
        launcher.up()
        launcher.wait_healthy(timeout_s=healthy_timeout_s)
        return launcher, endpoint

    yield _launch
    for launcher in launchers:
        launcher.down()
