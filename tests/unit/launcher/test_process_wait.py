"""Waiting on a service's process: however long it runs, the wait holds one task for its exit code."""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path

import pytest

from deploy.launcher import process as process_module
from deploy.launcher.process import ServiceProcess


def _exit_waits() -> int:
    """Pending tasks running a process's ``_exited`` coroutine."""
    return sum(
        1
        for task in asyncio.all_tasks()
        if not task.done() and getattr(task.get_coro(), "__name__", "") == "_exited"
    )


async def _wait_and_count(tmp_path: Path) -> tuple[int, int]:
    """Spawn a child that lives for 40 descendant scans; (its exit code, the most exit waits at once)."""
    proc = await ServiceProcess.spawn(
        [sys.executable, "-c", "import time; time.sleep(0.4)"],
        cwd=tmp_path,
        env={},
        on_line=lambda _line: None,
    )
    wait = asyncio.ensure_future(proc.wait())
    most = 0
    while not wait.done():
        most = max(most, _exit_waits())
        await asyncio.sleep(0.02)
    return wait.result(), most


def test_a_long_wait_keeps_one_task_for_the_exit(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The wait scans for descendants every ``DESCENDANT_SCAN_S``; each scan once started a fresh exit
    task that outlived its timeout, so a supervisor's memory grew with every service's uptime."""
    monkeypatch.setattr(process_module, "DESCENDANT_SCAN_S", 0.01)
    code, most = asyncio.run(_wait_and_count(tmp_path))
    assert code == 0
    assert most == 1, f"{most} tasks were waiting for one process's exit at once"
