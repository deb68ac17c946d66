"""A service that can never start ends ``up --wait``, ``demo`` and ``trials`` at once, as a user runs them:
one line naming the service, the cause and the fix, a failing exit status, and nothing left running (the
``mark`` fixture fails the test on any survivor).

The cause is put in with ``--service battery=COMMAND``, the way a user's replacement arrives: a command
that is not found, one that exits with a configuration error, one from a ``.venv-ros2`` that was never
built. A taken port ends ``up --wait`` (the stack's router listens where ``ZENOH_LISTEN`` says); ``demo`` and
``trials`` pick a free port of their own, so a taken one cannot stop them.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

from deploy.launcher.api import free_endpoint
from tests.support.processes import REPO_ROOT

#: The issue's bound: each command ends within 10 s of being started, cause included.
WITHIN_S = 10.0

CAUSES = {
    "command-not-found": ("/nonexistent/bin/battery", ("/nonexistent/bin/battery", "No such file")),
    "configuration-error": (f"{sys.executable} -c 'import sys; sys.exit(78)'", ("configuration error",)),
    "missing-ros2-venv": (".venv-ros2-absent/.venv-ros2/bin/python -m services.battery", ("run make ros2",)),
}


@pytest.fixture
def project() -> Iterator[str]:
    """A project name of its own for ``up``: its state directory goes when the test ends."""
    name = f"failfast-{uuid.uuid4().hex[:8]}"
    yield name
    shutil.rmtree(REPO_ROOT / ".zendock" / name, ignore_errors=True)


def _zendock(
    mark: str, *args: str, endpoint: str | None = None
) -> tuple[subprocess.CompletedProcess[str], float]:
    endpoint = endpoint or free_endpoint()
    env = {
        **os.environ,
        "ZENDOCK_TEST_MARK": mark,
        "PYTHONPATH": str(REPO_ROOT),
        "NO_COLOR": "1",
        "ZENOH_LISTEN": endpoint,
        "ZENOH_CONNECT": endpoint,
    }
    started = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-m", "deploy.cli", *args],
        cwd=REPO_ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    return done, time.monotonic() - started


def _command(name: str, project: str, tmp_path: Path) -> list[str]:
    if name == "up --wait":
        return ["up", "-p", project, "--wait", "--wait-timeout", "60"]
    if name == "demo":
        return ["demo", "--timeout", "60", "--runs-dir", str(tmp_path)]
    return ["trials", "--n", "1", "--runs-dir", str(tmp_path), "--timeout", "60"]


def _assert_ended_at_once(done: subprocess.CompletedProcess[str], took_s: float, *says: str) -> None:
    output = done.stdout + done.stderr
    assert done.returncode not in (0, None), f"exit {done.returncode}:\n{output}"
    assert took_s < WITHIN_S, f"took {took_s:.1f} s:\n{output}"
    last = done.stderr.strip().splitlines()[-1]
    for words in says:
        assert words in last, f"the last line does not say {words!r}: {last!r}\n{output}"
    assert "Traceback" not in output and ".rs:" not in output, output


@pytest.mark.parametrize("cause", CAUSES)
@pytest.mark.parametrize("command", ["up --wait", "demo", "trials"])
def test_a_service_that_cannot_start_ends_the_command_at_once(
    command: str, cause: str, mark: str, project: str, tmp_path: Path
) -> None:
    replacement, says = CAUSES[cause]
    args = [*_command(command, project, tmp_path), "--service", f"battery={replacement}"]
    done, took_s = _zendock(mark, *args)
    _assert_ended_at_once(done, took_s, "battery", *says)


def test_a_taken_port_ends_up_wait_with_the_port_and_the_fix(mark: str, project: str, tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        endpoint = f"tcp/127.0.0.1:{taken.getsockname()[1]}"
        done, took_s = _zendock(mark, *_command("up --wait", project, tmp_path), endpoint=endpoint)
    _assert_ended_at_once(done, took_s, "router", f"{endpoint} is in use", "ZENOH_LISTEN")
    last = done.stderr.strip().splitlines()[-1]
    # said once: a service that waited on the router is named, not given the router's cause again
    assert last.count(f"{endpoint} is in use") == 1, last
