"""One supervised OS process: its own session and process group, output pumped line by line, and a
stop that escalates SIGINT -> SIGTERM -> SIGKILL to the whole group (as ros2 launch does).

Processes are told apart by ``(pid, create_time)`` so a recycled pid is never signalled by mistake, and a
group counts as gone once only zombies are left (the container's init may never reap orphans).
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import psutil

POLL_S = 0.05
#: A service that exits by itself may leave helpers in its group: they get SIGTERM, then SIGKILL after this.
ORPHAN_GRACE_S = 1.0
#: How often the descendants of a running service are noted (to reap any that start their own session).
DESCENDANT_SCAN_S = 2.0
_READ_CHUNK = 65536
_MAX_LINE = 65536


def signal_group(pgid: int, sig: int) -> bool:
    """Send ``sig`` to a process group; False when the group no longer exists."""
    try:
        os.killpg(pgid, sig)
    except ProcessLookupError:
        return False
    except PermissionError:
        return False
    return True


def live_group_members(pgid: int) -> list[psutil.Process]:
    """Processes of group ``pgid`` that are not zombies."""
    try:
        os.killpg(pgid, 0)
    except (ProcessLookupError, PermissionError):
        return []
    members = []
    for proc in psutil.process_iter(["status"]):
        try:
            if os.getpgid(proc.pid) == pgid and proc.info["status"] != psutil.STATUS_ZOMBIE:
                members.append(proc)
        except (ProcessLookupError, psutil.Error):
            continue
    return members


def is_alive(proc: psutil.Process) -> bool:
    try:
        return bool(proc.is_running() and proc.status() != psutil.STATUS_ZOMBIE)
    except psutil.Error:
        return False


class GroupProcess(ABC):
    """A process that leads its own session and group: :meth:`wait` returns the exit code once the main
    process has exited and its group is gone; :meth:`stop` escalates signals until then. How the exit is
    learnt is the subclass's: :class:`ServiceProcess` is the supervisor's own child, :class:`ForkedChild` a
    warm standby's (:mod:`deploy.launcher.zygote`)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.pgid = pid  # a new session: the process leads its own session and group
        self.started_at = time.monotonic()
        try:
            self.create_time: float | None = psutil.Process(pid).create_time()
        except psutil.Error:
            self.create_time = None
        self._descendants: dict[int, psutil.Process] = {}
        self._stop_task: asyncio.Task[None] | None = None
        #: The one task that learns the exit code (:meth:`wait`'s scans all wait on it).
        self._exit_task: asyncio.Task[int] | None = None

    @property
    @abstractmethod
    def returncode(self) -> int | None:
        """The main process's exit code; None while it runs."""

    @abstractmethod
    async def _exited(self) -> int:
        """The main process's exit code, once it has exited."""

    @abstractmethod
    async def _output_done(self) -> None:
        """Once the process has exited: until its last output has been passed on."""

    def remember_descendants(self) -> None:
        """Note the main process's descendants now, so ones that left the group can still be reaped."""
        try:
            for child in psutil.Process(self.pid).children(recursive=True):
                self._descendants.setdefault(child.pid, child)
        except psutil.Error:
            pass

    def _leftovers(self) -> list[psutil.Process]:
        members = {p.pid: p for p in live_group_members(self.pgid)}
        for pid, proc in self._descendants.items():
            if pid not in members and is_alive(proc):
                members[pid] = proc
        return list(members.values())

    def _gone(self) -> bool:
        return self.returncode is not None and not self._leftovers()

    def _signal_all(self, sig: int) -> None:
        signal_group(self.pgid, sig)
        for proc in self._descendants.values():
            with contextlib.suppress(psutil.Error):
                if is_alive(proc):
                    proc.send_signal(sig)

    def send_signal(self, sig: int) -> None:
        """Signal the process group (``zendock kill``)."""
        self.remember_descendants()
        self._signal_all(sig)

    async def _until_gone(self, deadline: float) -> bool:
        while time.monotonic() < deadline:
            if self._gone():
                return True
            await asyncio.sleep(POLL_S)
        return self._gone()

    async def _escalate(self, steps: Sequence[tuple[int, float]]) -> None:
        """Send each signal at its offset (s) unless the group is gone by then; SIGKILL closes the list."""
        start = time.monotonic()
        for sig, offset_s in steps:
            if not await self._until_gone(start + offset_s):
                self._signal_all(sig)
            else:
                return
        await self._until_gone(time.monotonic() + 5.0)

    def stop(self, grace_s: float) -> asyncio.Task[None]:
        """SIGINT now, SIGTERM at half the grace period, SIGKILL at the end of it; idempotent."""
        if self._stop_task is None:
            self.remember_descendants()
            grace_s = max(grace_s, 0.0)
            self._stop_task = asyncio.ensure_future(
                self._escalate(
                    [(signal.SIGINT, 0.0), (signal.SIGTERM, grace_s / 2), (signal.SIGKILL, grace_s)]
                )
            )
        return self._stop_task

    async def wait(self) -> int:
        """The exit code (negative: killed by that signal) once the main process and its group are gone."""
        if self._exit_task is None:
            # One task for the life of the process. A fresh ``_exited()`` per scan left a task and an exit
            # waiter behind at every timeout, one every 2 s per service: zendock's own process grew for
            # as long as its stack ran.
            self._exit_task = asyncio.ensure_future(self._exited())
        while True:
            self.remember_descendants()
            try:
                async with asyncio.timeout(DESCENDANT_SCAN_S):
                    returncode = await asyncio.shield(self._exit_task)
                break
            except TimeoutError:
                continue
        if self._stop_task is not None:
            await asyncio.shield(self._stop_task)
        elif not self._gone():
            await self._escalate([(signal.SIGTERM, 0.0), (signal.SIGKILL, ORPHAN_GRACE_S)])
        await self._output_done()
        return returncode

    async def kill_now(self) -> None:
        """SIGKILL the group at once (second Ctrl-C, or a supervisor that must not wait)."""
        self.remember_descendants()
        self._signal_all(signal.SIGKILL)


class ServiceProcess(GroupProcess):
    """A child of the supervisor, started with :meth:`spawn`; its output is pumped line by line."""

    def __init__(self, proc: asyncio.subprocess.Process, on_line: Callable[[str], None]) -> None:
        super().__init__(proc.pid)
        self._proc = proc
        self._pump = asyncio.ensure_future(self._pump_output(on_line))

    @classmethod
    async def spawn(
        cls,
        argv: Sequence[str],
        *,
        cwd: Path,
        env: Mapping[str, str],
        on_line: Callable[[str], None],
        standby: bool = False,
        pass_fds: Sequence[int] = (),
    ) -> ServiceProcess:
        """Start ``argv`` in a new session; stdout and stderr are merged (ordering kept) into ``on_line``.

        A ``standby`` (:mod:`deploy.standby`) gets a pipe for standard input (:meth:`write`); anything else
        reads /dev/null. ``pass_fds`` stay open in the child.
        """
        proc = await asyncio.create_subprocess_exec(
            *argv,
            cwd=str(cwd),
            env=dict(env),
            stdin=asyncio.subprocess.PIPE if standby else asyncio.subprocess.DEVNULL,
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.STDOUT,
            start_new_session=True,
            pass_fds=tuple(pass_fds),
        )
        return cls(proc, on_line)

    @property
    def returncode(self) -> int | None:
        return self._proc.returncode

    async def _exited(self) -> int:
        return await self._proc.wait()

    async def _output_done(self) -> None:
        try:
            async with asyncio.timeout(1.0):
                await asyncio.shield(self._pump)
        except TimeoutError:
            self._pump.cancel()

    def close_input(self) -> None:
        """End a standby's input: it exits, and forks nothing more."""
        if self._proc.stdin is not None and not self._proc.stdin.is_closing():
            self._proc.stdin.close()

    async def write(self, data: bytes) -> bool:
        """Write to a standby's input; False when it can no longer read it (it has exited)."""
        stdin = self._proc.stdin
        if stdin is None or stdin.is_closing() or self._proc.returncode is not None:
            return False
        try:
            stdin.write(data)
            await stdin.drain()
        except (BrokenPipeError, ConnectionResetError):
            return False
        return True

    async def _pump_output(self, on_line: Callable[[str], None]) -> None:
        assert self._proc.stdout is not None
        pending = b""
        while True:
            chunk = await self._proc.stdout.read(_READ_CHUNK)
            if not chunk:
                break
            pending += chunk
            *lines, pending = pending.split(b"\n")
            while len(pending) > _MAX_LINE:
                lines.append(pending[:_MAX_LINE])
                pending = pending[_MAX_LINE:]
            for raw in lines:
                on_line(raw.decode("utf-8", errors="replace").rstrip("\r"))
        if pending:
            on_line(pending.decode("utf-8", errors="replace").rstrip("\r"))


class ForkedChild(GroupProcess):
    """A service forked by its warm standby (:mod:`deploy.launcher.zygote`): the standby is its parent, so
    its exit comes from the standby's report; its output comes through the standby's own pipe."""

    def __init__(self, pid: int, exit_code: asyncio.Future[int]) -> None:
        super().__init__(pid)
        self._exit_code = exit_code

    @property
    def returncode(self) -> int | None:
        return self._exit_code.result() if self._exit_code.done() else None

    async def _exited(self) -> int:
        return await self._exit_code

    async def _output_done(self) -> None:
        """Its output comes through the standby's pipe, which outlives it: nothing to wait for here."""
        return None
