"""A ``zendock`` command that runs a stack through the launcher's API brings it down when terminated.

SIGTERM is what a CI timeout, ``kill`` or a process supervisor sends; it must unwind like Ctrl-C so no
service of the stack outlives the command.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import uuid
from pathlib import Path

import psutil

from tests.integration.launcher.conftest import kill_marked, marked_processes
from tests.support.processes import free_port, wait_until

REPO_ROOT = Path(__file__).resolve().parents[2]


def _services(mark: str) -> list[str]:
    names = []
    for proc in marked_processes(mark):
        try:
            names += [arg for arg in proc.cmdline() if arg.startswith("services.")]
        except psutil.Error:
            continue
    return names


def test_sigterm_to_demo_brings_its_stack_down(tmp_path: Path) -> None:
    mark = uuid.uuid4().hex
    env = {**os.environ, "ZENDOCK_TEST_MARK": mark, "NO_COLOR": "1", "PYTHONPATH": str(REPO_ROOT)}
    demo = subprocess.Popen(
        [sys.executable, "-m", "deploy.cli", "demo", "--rtf", "1", "--timeout", "600"],
        cwd=REPO_ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        wait_until(
            lambda: {"services.simulator", "services.docking"} <= set(_services(mark)),
            90.0,
            lambda: f"the demo's stack did not come up; running: {_services(mark)}",
        )
        demo.send_signal(signal.SIGTERM)
        try:
            demo.wait(60)
        except subprocess.TimeoutExpired:
            raise AssertionError("zendock demo did not exit within 60 s of SIGTERM") from None
        wait_until(
            lambda: not marked_processes(mark),
            15.0,
            lambda: f"left behind after SIGTERM: {[(p.pid, p.cmdline()) for p in marked_processes(mark)]}",
        )
    finally:
        if demo.poll() is None:
            demo.kill()
            demo.wait()
        kill_marked(mark)


def test_a_service_still_waiting_for_its_router_ends_on_sigterm_with_0(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """The contract's duty holds before the session is open: zenoh.open blocks in native code while no router
    answers, so the service connects on a helper thread and its main thread still runs the SIGTERM handler."""
    log = tmp_path / "battery.log"
    with log.open("wb") as out:
        proc = subprocess.Popen(
            [sys.executable, "-m", "services.battery", "--connect", f"tcp/127.0.0.1:{free_port()}"],
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    try:
        wait_until(lambda: "connecting to" in log.read_text(), 20.0, lambda: log.read_text())
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=2.0) == 0, log.read_text()
        assert "stopped before the router answered" in log.read_text()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
