"""The supervisor's side of a warm standby (:mod:`deploy.standby`): start it, ask it for a service, learn
when each service it forked exits.

The standby is the supervisor's child; the services it forks are the standby's. Their exits come as the
standby's reports (``started PID``, ``exited PID CODE``) on a pipe of their own, read here.
"""

from __future__ import annotations

import asyncio
import os
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import psutil

from deploy.launcher.process import POLL_S, ForkedChild, ServiceProcess
from deploy.standby import GO, STATUS_FD_ENV

#: A standby holds no session: SIGINT ends it at once, SIGKILL after this.
STANDBY_GRACE_S = 2.0
#: How long a standby has to leave by itself at the end of its input.
CLOSE_QUIETLY_S = 1.0
#: How long a fork may take to be reported: the standby may still be importing (seconds on a loaded machine).
FORK_TIMEOUT_S = 60.0
#: The exit code of a forked service whose standby died first: nobody can learn the real one.
EXIT_UNKNOWN = 255


class Zygote:
    """A running standby. Create with :meth:`spawn`; :meth:`fork` starts its service, :meth:`close` ends it."""

    def __init__(self, process: ServiceProcess, on_ready: Callable[[], None] | None = None) -> None:
        self.process = process
        self._on_ready = on_ready
        self._waiting: deque[asyncio.Future[int | None]] = deque()
        #: Each forked service's exit, from its fork's report until both the exit is known and the service
        #: has been handed out (either may come first).
        self._exits: dict[int, asyncio.Future[int]] = {}
        self._handed_out: set[int] = set()
        self._reader: asyncio.Task[None] | None = None
        #: Its imports are done: a fork now starts the service at once.
        self.ready = False

    @classmethod
    async def spawn(
        cls,
        argv: Sequence[str],
        *,
        cwd: Path,
        env: Mapping[str, str],
        on_line: Callable[[str], None],
        on_ready: Callable[[], None] | None = None,
    ) -> Zygote:
        """Start ``argv`` (``python -m deploy.standby services.<name> FLAGS``); its output and its
        services' go to ``on_line``; ``on_ready`` is called once its imports are done. Raises
        :class:`OSError` when it cannot start."""
        read_fd, write_fd = os.pipe()
        try:
            process = await ServiceProcess.spawn(
                argv,
                cwd=cwd,
                env={**env, STATUS_FD_ENV: str(write_fd)},
                on_line=on_line,
                standby=True,
                pass_fds=(write_fd,),
            )
        except BaseException:
            os.close(read_fd)
            raise
        finally:
            os.close(write_fd)
        zygote = cls(process, on_ready)
        reader = asyncio.StreamReader()
        loop = asyncio.get_running_loop()
        await loop.connect_read_pipe(
            lambda: asyncio.StreamReaderProtocol(reader), os.fdopen(read_fd, "rb", buffering=0)
        )
        zygote._reader = asyncio.ensure_future(zygote._read(reader))
        return zygote

    @property
    def alive(self) -> bool:
        return self.process.returncode is None and self._reader is not None and not self._reader.done()

    def _exit_of(self, pid: int) -> asyncio.Future[int]:
        return self._exits.setdefault(pid, asyncio.get_running_loop().create_future())

    async def _read(self, reader: asyncio.StreamReader) -> None:
        while line := await reader.readline():
            words = line.decode("utf-8", errors="replace").split()
            if words == ["ready"]:
                self.ready = True
                if self._on_ready is not None:
                    self._on_ready()
            elif len(words) == 2 and words[0] == "started" and words[1].isdigit():
                pid = int(words[1])
                self._exit_of(pid)
                if self._waiting:
                    self._waiting.popleft().set_result(pid)
            elif len(words) == 3 and words[0] == "exited" and words[1].isdigit():
                pid = int(words[1])
                exit_code = self._exit_of(pid)
                if not exit_code.done():
                    exit_code.set_result(int(words[2]))
                if pid in self._handed_out:
                    self._handed_out.discard(pid)
                    del self._exits[pid]
        # The standby has gone: nothing more will be forked or reported.
        while self._waiting:
            self._waiting.popleft().set_result(None)
        for pid, exit_code in self._exits.items():
            if not exit_code.done():
                asyncio.ensure_future(_orphan_exit(pid, exit_code))

    async def fork(self) -> ForkedChild | None:
        """Start the service; None when the standby cannot (it has exited, or never reported the fork)."""
        if not self.alive:
            return None
        started: asyncio.Future[int | None] = asyncio.get_running_loop().create_future()
        self._waiting.append(started)
        if not await self.process.write(GO):
            self._waiting.remove(started)
            return None
        try:
            async with asyncio.timeout(FORK_TIMEOUT_S):
                pid = await started
        except TimeoutError:
            return None
        if pid is None:
            return None
        exit_code = self._exits[pid]
        if exit_code.done():
            del self._exits[pid]
        else:
            self._handed_out.add(pid)
        return ForkedChild(pid, exit_code)

    async def close(self) -> int:
        """End the standby and wait until it is gone: the end of its input ends it at once, signals follow
        only if it does not (it may be deep in an import)."""
        self.process.close_input()
        try:
            async with asyncio.timeout(CLOSE_QUIETLY_S):
                code = await self.process.wait()
        except TimeoutError:
            self.process.stop(STANDBY_GRACE_S)
            code = await self.process.wait()
        if self._reader is not None:
            await self._reader
        return code

    async def kill_now(self) -> None:
        await self.process.kill_now()


async def _orphan_exit(pid: int, exit_code: asyncio.Future[int]) -> None:
    """A service whose standby died first: its exit is known only by its absence."""
    started = time.monotonic()
    while True:
        try:
            if psutil.Process(pid).status() == psutil.STATUS_ZOMBIE:
                break
        except psutil.NoSuchProcess:
            break
        await asyncio.sleep(POLL_S if time.monotonic() - started < 5.0 else 1.0)
    if not exit_code.done():
        exit_code.set_result(EXIT_UNKNOWN)
