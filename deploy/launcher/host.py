"""A supervisor with its runtime directory: the state file, the control socket, and the run until ``down``.

The same host runs behind ``zendock up`` in the foreground, the ``up -d`` daemon, and the Python API, so
``ps``, ``logs``, ``stop`` and ``down`` work from another shell whichever started the stack.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import signal
import time
from collections.abc import Callable, Sequence
from typing import Any

import psutil

from deploy.launcher.plan import LaunchPlan
from deploy.launcher.restart import Backoff
from deploy.launcher.runtime import (
    ControlError,
    RuntimePaths,
    clear_runtime,
    start_new_logs,
    stop_orphans,
    supervisor_info,
    write_json_atomic,
)
from deploy.launcher.supervisor import Supervisor

STATE_WRITE_INTERVAL_S = 0.1
#: ``start``/``restart`` requests answer once the services run, or after this long (waiting on dependencies).
START_WAIT_S = 30.0


def op_name(line: bytes) -> str:
    try:
        return str(json.loads(line).get("op"))
    except (ValueError, AttributeError):
        return "request"


class SupervisorHost:
    """Owns one :class:`Supervisor` for a project. Use :meth:`run` as the body of an event loop."""

    def __init__(
        self,
        plan: LaunchPlan,
        services: Sequence[str],
        paths: RuntimePaths,
        *,
        mode: str,
        backoff: Backoff | None = None,
        on_line: Callable[[str, str], None] | None = None,
        exit_when_settled: bool = False,
    ) -> None:
        self.plan = plan
        self.services = list(services)
        self.paths = paths
        self.mode = mode
        self.backoff = backoff
        self.on_line = on_line
        self.exit_when_settled = exit_when_settled
        self.supervisor: Supervisor | None = None
        self.ready = asyncio.Event()
        self._down_requested = asyncio.Event()
        self._down_task: asyncio.Task[None] | None = None
        self._write_pending = False
        self._last_write = 0.0
        self._server: asyncio.AbstractServer | None = None
        self._connections: set[asyncio.Task[Any]] = set()
        self._closed = False
        self.interrupted = False

    # -- runtime files ---------------------------------------------------------------------------
    def claim(self) -> None:
        """Refuse to run next to a live supervisor of the same project; write our record."""
        other = supervisor_info(self.paths)
        if other is not None and other.get("pid") != os.getpid():
            raise ControlError(
                f"project {self.plan.project} is already up (supervisor pid {other['pid']}); run `zendock down` first"
            )
        stop_orphans(self.paths)
        clear_runtime(self.paths)
        start_new_logs(self.paths)
        me = psutil.Process()
        write_json_atomic(
            self.paths.supervisor_file,
            {
                "pid": me.pid,
                "create_time": me.create_time(),
                "socket": str(self.paths.socket_path),
                "mode": self.mode,
                "project": self.plan.project,
                "namespace": self.plan.namespace,
                "connect": list(self.plan.connect),
                "started_at": time.time(),
            },
        )

    def _schedule_state_write(self) -> None:
        if self._write_pending:
            return
        self._write_pending = True
        delay = max(0.0, self._last_write + STATE_WRITE_INTERVAL_S - time.monotonic())
        asyncio.get_running_loop().call_later(delay, self._write_state)

    def _write_state(self) -> None:
        self._write_pending = False
        self._last_write = time.monotonic()
        if self.supervisor is None or self._closed:
            return
        with contextlib.suppress(OSError):
            write_json_atomic(
                self.paths.state_file,
                {
                    "project": self.plan.project,
                    "updated_at": time.time(),
                    "services": [status.to_dict() for status in self.supervisor.statuses()],
                },
            )

    # -- control socket ----------------------------------------------------------------------------
    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        if task is not None:
            self._connections.add(task)
            task.add_done_callback(self._connections.discard)
        try:
            line = await reader.readline()
            try:
                request = json.loads(line)
                reply = await self.handle(request)
            except (ValueError, KeyError) as exc:
                reply = {"ok": False, "error": str(exc).strip("'\"")}
            except Exception as exc:  # a bad request must not take the supervisor down
                reply = {"ok": False, "error": f"{op_name(line)} failed: {exc!r}"}
            writer.write(json.dumps(reply).encode() + b"\n")
            await writer.drain()
        except (ConnectionError, asyncio.IncompleteReadError):
            pass
        finally:
            writer.close()

    async def handle(self, request: dict[str, Any]) -> dict[str, Any]:
        """One control request: ps | start | stop | restart | kill | down | info."""
        assert self.supervisor is not None
        op = request.get("op")
        names = list(request.get("services") or [])
        sup = self.supervisor
        if op == "ps":
            pass
        elif op == "info":
            return {
                "ok": True,
                "project": self.plan.project,
                "pid": os.getpid(),
                "mode": self.mode,
                "services": list(sup.runners),
            }
        elif op == "start":
            order = sup.start(names or self.services)
            await sup.wait_started(order, START_WAIT_S)
        elif op == "stop":
            await sup.stop(names or list(sup.runners))
        elif op == "restart":
            await sup.restart(names or list(sup.runners))
            await sup.wait_started(names or list(sup.runners), START_WAIT_S)
        elif op == "kill":
            signalled = sup.kill(names or list(sup.runners), int(request.get("signal", signal.SIGKILL)))
            return {
                "ok": True,
                "signalled": signalled,
                "services": [status.to_dict() for status in sup.statuses()],
            }
        elif op == "down":
            await self.down()
            statuses = {status.name: status for status in sup.statuses()}
            return {"ok": True, "services": [statuses[name].to_dict() for name in sup.stop_order(statuses)]}
        else:
            return {"ok": False, "error": f"unknown request {op!r}"}
        return {"ok": True, "services": [status.to_dict() for status in sup.statuses()]}

    # -- run ---------------------------------------------------------------------------------------
    def request_down(self) -> None:
        self._down_requested.set()

    async def down(self) -> None:
        """Stop every service (dependents first); idempotent, concurrent callers share the work."""
        if self._down_task is None:
            assert self.supervisor is not None
            self._down_task = asyncio.ensure_future(self.supervisor.close())
        self._down_requested.set()
        await asyncio.shield(self._down_task)

    async def force_kill(self) -> None:
        if self.supervisor is not None:
            await self.supervisor.kill_all_now()

    async def run(self) -> int:
        """Start the services, serve until ``down`` (or settled, in the foreground), clean up.

        Returns 0, or 1 when the stack ended by itself with a service that failed.
        """
        self.claim()
        self.supervisor = Supervisor(
            self.plan,
            backoff=self.backoff,
            log_dir=self.paths.logs_dir,
            on_line=self.on_line,
            on_change=self._schedule_state_write,
        )
        exit_code = 0
        try:
            socket_path = self.paths.socket_path
            with contextlib.suppress(FileNotFoundError):
                socket_path.unlink()
            self._server = await asyncio.start_unix_server(self._serve, path=str(socket_path))
            self.supervisor.open()
            self.supervisor.start(self.services)
            self._write_state()
            self.ready.set()
            settled = asyncio.ensure_future(self._settled()) if self.exit_when_settled else None
            down = asyncio.ensure_future(self._down_requested.wait())
            waiters = [task for task in (settled, down) if task is not None]
            finished, _ = await asyncio.wait(waiters, return_when=asyncio.FIRST_COMPLETED)
            for task in waiters:
                task.cancel()
            if settled is not None and settled in finished and not self._down_requested.is_set():
                failed = [s for s in self.supervisor.statuses() if s.exit_code not in (0, None)]
                exit_code = 1 if failed else 0
        finally:
            await self.down()
            if self._server is not None:
                self._server.close()
            current = asyncio.current_task()
            pending = [task for task in self._connections if task is not current]
            if pending:
                await asyncio.wait(pending, timeout=2.0)
            self._closed = True
            clear_runtime(self.paths)
        return exit_code

    async def _settled(self) -> None:
        assert self.supervisor is not None
        await self.supervisor.wait_until(self.supervisor.settled, None)


def run_blocking(host: SupervisorHost, *, announce: Callable[[str], None] | None = None) -> int:
    """Run ``host`` on a new event loop in this (main) thread until ``down``, SIGINT or SIGTERM.

    The first signal stops every service gracefully; a second one kills what is left at once.
    """

    async def main() -> int:
        loop = asyncio.get_running_loop()

        def on_signal(signum: int) -> None:
            if not host.interrupted:
                host.interrupted = True
                if announce is not None:
                    announce(f"{signal.Signals(signum).name}: stopping every service (again to kill at once)")
                host.request_down()
            else:
                if announce is not None:
                    announce("killing every service")
                asyncio.ensure_future(host.force_kill())

        for signum in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(signum, on_signal, signum)
        try:
            return await host.run()
        finally:
            for signum in (signal.SIGINT, signal.SIGTERM):
                loop.remove_signal_handler(signum)

    return asyncio.run(main())
