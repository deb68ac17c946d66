"""Fixtures shared by every test: a router on a free port, a fresh namespace, service processes."""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
import zenoh

from shared.session import SessionSpec, open_session
from tests.support.processes import ServiceProcess, free_port


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
