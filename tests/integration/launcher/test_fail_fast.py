"""A service that can never start ends the wait at once, with one line naming it and why, and is not restarted."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from deploy.launcher import Launcher
from deploy.launcher.api import ServiceFailed
from deploy.launcher.launch import read_command
from deploy.paths import REPO_ROOT
from tests.integration.launcher.conftest import fake

#: The issue's bound: the run ends within about 5 s of the cause being certain; the tests allow 10.
WITHIN_S = 10.0


def _fails_fast(stack: Launcher, service: str) -> str:
    started = time.monotonic()
    with pytest.raises(ServiceFailed) as failed:
        stack.wait_healthy(timeout_s=60.0)
    assert time.monotonic() - started < WITHIN_S, "the wait did not end when the service failed for good"
    status = {s.name: s for s in stack.ps()}[service]
    assert status.state == "exited" and status.restarts == 0, "a service that cannot start is not restarted"
    assert "Traceback" not in failed.value.summary and ".rs:" not in failed.value.summary
    return failed.value.summary


def test_a_command_not_found_ends_the_wait_with_its_name(launch) -> None:  # type: ignore[no-untyped-def]
    stack = launch(
        """\
        services:
          ghost:
            command: [/nonexistent/bin/program, --flag]
            restart: on-failure
            healthcheck: {liveliness: true, timeout: 30s}
        """
    )
    summary = _fails_fast(stack, "ghost")
    assert summary.startswith("ghost cannot start: ") and "/nonexistent/bin/program" in summary


def test_a_missing_ros2_venv_says_to_run_make_ros2(launch) -> None:  # type: ignore[no-untyped-def]
    stack = launch(
        """\
        services:
          ros2_dds:
            command: [.venv-ros2-absent/.venv-ros2/bin/python, -m, services.ros2_dds]
            restart: on-failure
            healthcheck: {liveliness: true, timeout: 30s}
        """
    )
    assert "run make ros2" in _fails_fast(stack, "ros2_dds")


def test_a_configuration_error_ends_the_wait_and_is_not_restarted(launch) -> None:  # type: ignore[no-untyped-def]
    stack = launch(
        f"""\
        services:
          broken:
            command: {fake("--name", "broken", "--exit-after", "0.1", "--exit-code", "2")}
            restart: always
            healthcheck: {{liveliness: true, timeout: 30s}}
        """
    )
    assert _fails_fast(stack, "broken").startswith("broken cannot start")


def test_a_router_whose_port_is_taken_says_so_and_exits_2() -> None:
    with socket.socket() as taken:
        taken.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = subprocess.run(
            [sys.executable, "-m", "deploy.cli", "router", "--listen", f"tcp/127.0.0.1:{port}"],
            cwd=REPO_ROOT,
            capture_output=True,
            text=True,
            timeout=60,
            check=False,
        )
    assert done.returncode == 2, done.stderr
    line = done.stderr.strip().splitlines()[-1]
    assert line.startswith(
        f"zendock router: tcp/127.0.0.1:{port} is in use: set ZENOH_LISTEN and ZENOH_CONNECT"
    )
    assert ".rs:" not in done.stderr


def test_a_stack_file_command_reads_as_written(tmp_path: Path) -> None:
    # The missing interpreter above is read as zendock's ros2_dds service run by another python, as the
    # shipped stack runs it (so replacements and conform still know it).
    run = read_command([".venv-ros2/bin/python", "-m", "services.ros2_dds"])
    assert getattr(run, "service", None) == "ros2_dds"
