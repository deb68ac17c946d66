"""Launcher test fixtures: stacks of fake services on a free port, and a check that nothing is left behind.

Every process a test's stack starts carries ``ZENDOCK_TEST_MARK=<unique>`` in its environment (children
inherit it, grandchildren too), so a psutil scan finds any survivor, whatever its parent or session.
"""

from __future__ import annotations

import sys
import textwrap
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import psutil
import pytest

from deploy.launcher import Backoff, Launcher, free_endpoint, load_stack

FAKE_SERVICE = Path(__file__).with_name("fake_service.py")
FAST_BACKOFF = Backoff(initial_s=0.05, max_s=0.2, reset_after_s=10.0)


def marked_processes(mark: str) -> list[psutil.Process]:
    """Live (non-zombie) processes whose environment carries ``mark``."""
    found = []
    for proc in psutil.process_iter(["status"]):
        try:
            if proc.info["status"] == psutil.STATUS_ZOMBIE:
                continue
            if proc.environ().get("ZENDOCK_TEST_MARK") == mark:
                found.append(proc)
        except psutil.Error:
            continue
    return found


def kill_marked(mark: str) -> None:
    for proc in marked_processes(mark):
        try:
            proc.kill()
        except psutil.Error:
            pass


def wait_for(predicate: Callable[[], object], timeout_s: float, what: str) -> object:
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s}s waiting for {what}")
        time.sleep(0.02)


def fake(*args: str) -> str:
    """A YAML flow list: the command line of a fake service."""
    words = ["python", str(FAKE_SERVICE), *args]
    return "[" + ", ".join(f'"{w}"' for w in words) + "]"


@pytest.fixture
def mark() -> Iterator[str]:
    """A unique environment mark; asserts at teardown that no marked process survives."""
    value = uuid.uuid4().hex
    yield value
    survivors = marked_processes(value)
    kill_marked(value)
    assert not survivors, f"processes left behind: {[(p.pid, p.cmdline()) for p in survivors]}"


@pytest.fixture
def write_stack(tmp_path: Path) -> Callable[[str], Path]:
    def write(text: str) -> Path:
        path = tmp_path / "stack.yaml"
        path.write_text(textwrap.dedent(text), encoding="utf-8")
        return path

    return write


@pytest.fixture
def launch(tmp_path: Path, mark: str, router_endpoint: str) -> Iterator[Callable[..., Launcher]]:
    """``launch(stack_text, **launcher_options)``: a started Launcher on the test router, downed at teardown."""
    started: list[Launcher] = []

    def start(text: str, **options: object) -> Launcher:
        path = tmp_path / f"stack{len(started)}.yaml"
        path.write_text(textwrap.dedent(text), encoding="utf-8")
        stack = load_stack(path, env={}, project_dir=tmp_path)
        options.setdefault("connect", [router_endpoint])
        options.setdefault("namespace", f"t{uuid.uuid4().hex[:8]}")
        options.setdefault("backoff", FAST_BACKOFF)
        launcher = Launcher(
            stack,
            project_dir=tmp_path,
            environment={"ZENDOCK_TEST_MARK": mark},
            **options,  # type: ignore[arg-type]
        )
        started.append(launcher)
        return launcher.up()

    yield start
    for launcher in started:
        launcher.down()


@pytest.fixture
def endpoint() -> str:
    return free_endpoint()


def read_records(path: Path) -> list[tuple[str, str, float, int]]:
    if not path.exists():
        return []
    rows = []
    for line in path.read_text(encoding="utf-8").splitlines():
        name, event, when, pid = line.split()
        rows.append((name, event, float(when), int(pid)))
    return rows


PYTHON = sys.executable
