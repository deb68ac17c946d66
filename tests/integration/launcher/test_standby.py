"""A supervisor that keeps warm standbys: a killed service comes back from its standby, and none is left."""

from __future__ import annotations

import asyncio
import os
import signal
import sys
from pathlib import Path

import psutil

from deploy.commands.ps import format_table
from deploy.launcher.plan import ZENDOCK_ROOT
from deploy.launcher.zygote import Zygote
from tests.integration.launcher.conftest import marked_processes, wait_for

#: One restartable zendock service with a liveliness healthcheck.
BATTERY = """\
services:
  battery:
    command: [python, -m, services.battery]
    restart: on-failure
    healthcheck: {liveliness: true, timeout: 30s}
"""


def _standbys(mark: str) -> list[psutil.Process]:
    """The standbys: processes of ``deploy.standby`` whose parent is not one (the services it forked share
    its command line)."""
    found = [p for p in marked_processes(mark) if "deploy.standby" in p.cmdline()]
    pids = {p.pid for p in found}
    return [p for p in found if p.ppid() not in pids]


def test_a_killed_service_is_forked_again_by_its_warm_standby(launch, mark: str) -> None:  # type: ignore[no-untyped-def]
    stack = launch(BATTERY, standby=True)
    before = stack.wait_healthy(timeout_s=40)
    stack.wait_until(lambda st: st["battery"].standby == "ready", 30, "the warm standby ready")
    first = _standbys(mark)
    assert len(first) == 1 and first[0].pid != before["battery"].pid
    assert "warm standby ready" in format_table(stack.ps())
    os.kill(before["battery"].pid, signal.SIGKILL)
    after = stack.wait_until(
        lambda st: st["battery"].restarts == 1 and st["battery"].health == "healthy",
        30,
        "the killed battery back and healthy",
    )
    assert psutil.Process(after["battery"].pid).ppid() == first[0].pid, "not forked by the standby"
    assert any("from its warm standby" in line for line in stack.logs("battery"))
    assert [p.pid for p in _standbys(mark)] == [first[0].pid], "the standby stays ready for the next restart"
    os.kill(after["battery"].pid, signal.SIGKILL)  # and the next restart is forked by it too
    again = stack.wait_until(
        lambda st: st["battery"].restarts == 2 and st["battery"].health == "healthy",
        30,
        "the battery killed again back and healthy",
    )
    assert psutil.Process(again["battery"].pid).ppid() == first[0].pid
    assert stack.status("battery").last_exit.startswith("killed by signal 9")
    stack.down()
    assert not marked_processes(mark)
    assert not any("warm standby:" in line for line in stack.logs("battery")), "a standby printed something"


def test_without_the_option_no_standby_runs(launch, mark: str) -> None:  # type: ignore[no-untyped-def]
    stack = launch(BATTERY)
    stack.wait_healthy(timeout_s=40)
    assert not _standbys(mark) and stack.status("battery").standby == ""


def test_a_forked_service_that_exits_at_once_is_waited_for_with_its_code(tmp_path: Path) -> None:
    """The exit may be reported before the fork is handed out: the code still reaches the waiter."""

    async def scenario() -> tuple[int, int]:
        lines: list[str] = []
        argv = [sys.executable, "-m", "deploy.standby", "services.battery", "--no-such-flag"]
        zygote = await Zygote.spawn(argv, cwd=ZENDOCK_ROOT, env=dict(os.environ), on_line=lines.append)
        try:
            child = await zygote.fork()
            assert child is not None
            first = await asyncio.wait_for(child.wait(), 30)
            again = await zygote.fork()
            assert again is not None and again.pid != child.pid
            return first, await asyncio.wait_for(again.wait(), 30)
        finally:
            assert await zygote.close() == 0
            assert not zygote.alive

    assert asyncio.run(scenario()) == (2, 2)


def test_when_the_standby_has_died_the_restart_starts_cold(launch, mark: str) -> None:  # type: ignore[no-untyped-def]
    stack = launch(BATTERY, standby=True)
    before = stack.wait_healthy(timeout_s=40)
    standby = wait_for(lambda: _standbys(mark), 30, "a warm standby once the battery is healthy")[0]
    standby.kill()  # the supervisor reaps it (a wait here would take its exit status away)
    wait_for(lambda: not psutil.pid_exists(standby.pid), 10, "the standby reaped")
    os.kill(before["battery"].pid, signal.SIGKILL)
    after = stack.wait_until(
        lambda st: st["battery"].restarts == 1 and st["battery"].health == "healthy",
        30,
        "the killed battery back and healthy",
    )
    assert psutil.Process(after["battery"].pid).ppid() == os.getpid(), "not a cold start by the supervisor"
    assert any("warm standby gone (killed by signal 9)" in line for line in stack.logs("battery"))
    wait_for(lambda: _standbys(mark), 30, "a new standby once the battery is healthy again")
