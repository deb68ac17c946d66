"""The Python API: bring a stack up from a test or a demo, the way ``zendock up`` does, and always down.

The supervisor runs on its own event loop in a background thread of the calling process; the same runtime
directory is written as by ``zendock up``, so ``zendock ps -p <project>`` works alongside.
"""

from __future__ import annotations

import asyncio
import atexit
import signal
import socket
import threading
import time
from collections.abc import Callable, Coroutine, Iterable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, TextIO, TypeVar

from deploy.launcher.host import SupervisorHost
from deploy.launcher.logs import failure_line, tail
from deploy.launcher.plan import LaunchPlan, plan_launch
from deploy.launcher.printer import Printer
from deploy.launcher.restart import Backoff
from deploy.launcher.runtime import RuntimePaths
from deploy.launcher.stack_file import Stack, load_stack
from deploy.launcher.status import ServiceStatus
from deploy.launcher.supervisor import Supervisor

T = TypeVar("T")


def free_tcp_port(host: str = "127.0.0.1") -> int:
    """A TCP port nobody listens on right now (the OS picks it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind((host, 0))
        return int(probe.getsockname()[1])


def free_endpoint(host: str = "127.0.0.1") -> str:
    """A Zenoh endpoint on a free port, e.g. ``tcp/127.0.0.1:40123``."""
    return f"tcp/{host}:{free_tcp_port(host)}"


def is_ready(status: ServiceStatus) -> bool:
    """Running and healthy (or without a healthcheck), or a one-shot step that completed successfully."""
    if status.state == "running":
        return status.health in ("healthy", "none")
    return status.phase == "exited" and status.exit_code == 0


class StackNotReady(TimeoutError):
    """``wait_healthy`` / ``wait_until`` timed out; the message holds every service's status, ``summary`` one
    line naming what was not ready and the last line it printed."""

    def __init__(self, message: str, summary: str = "") -> None:
        super().__init__(message)
        self.summary = summary or message.splitlines()[0]


class ServiceFailed(StackNotReady):
    """A service the wait was for has ended and will not be started again (a configuration error, a command
    not found, a crash with restarts spent): the wait ends at once, its ``summary`` naming the service and why."""


def failed_for_good(status: ServiceStatus) -> bool:
    """Ended by itself with a failure and left down: no restart is coming."""
    return status.phase == "exited" and status.exit_code not in (None, 0)


def format_statuses(statuses: Iterable[ServiceStatus]) -> str:
    return "\n".join(
        f"  {s.name}: {s.state} pid={s.pid} restarts={s.restarts} health={s.health} {s.detail}".rstrip()
        for s in statuses
    )


class Launcher:
    """Runs a stack's services until :meth:`down`; a context manager that downs on exit, error or not.

    ``stack`` is a :class:`Stack` or a stack file path. ``services``/``profiles`` select what starts (as
    ``up`` does); ``namespace``, ``connect`` and ``environment`` override the stack's settings for every
    service; ``project_dir`` holds ``.zendock/<project>/`` (logs, state); services run in ``working_dir``
    (default: the current directory). ``output`` receives every line with a ``name |`` prefix.
    """

    def __init__(
        self,
        stack: Stack | str | Path,
        *,
        services: Sequence[str] = (),
        profiles: Sequence[str] = (),
        project_dir: str | Path | None = None,
        project_name: str | None = None,
        working_dir: str | Path | None = None,
        namespace: str | None = None,
        connect: Sequence[str] | None = None,
        environment: Mapping[str, str] | None = None,
        backoff: Backoff | None = None,
        output: TextIO | None = None,
        standby: bool = False,
    ) -> None:
        self.project_dir = Path(project_dir).resolve() if project_dir is not None else Path.cwd()
        if not isinstance(stack, Stack):
            stack = load_stack(stack, project_dir=self.project_dir)
        self.stack = stack
        self.project = project_name or stack.project_name
        self.services = stack.select(services, profiles)
        self.plan: LaunchPlan = plan_launch(
            stack,
            working_dir=working_dir if working_dir is not None else Path.cwd(),
            namespace=namespace,
            connect=connect,
            environment=environment,
            standby=standby,
        )
        if project_name:
            self.plan = replace(self.plan, project=project_name)
        self.paths = RuntimePaths.for_project(self.project_dir, self.project)
        self._backoff = backoff
        self._printer = Printer(output, self.services) if output is not None else None
        self._host: SupervisorHost | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self.exit_code: int | None = None

    # -- lifecycle -----------------------------------------------------------------------------------
    @property
    def namespace(self) -> str:
        return self.plan.namespace

    @property
    def connect(self) -> tuple[str, ...]:
        return self.plan.connect

    def __enter__(self) -> Launcher:
        self.up()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.down()

    def up(self, timeout_s: float = 30.0) -> Launcher:
        """Start the supervisor and the selected services (in dependency order); returns at once."""
        if self._thread is not None:
            raise RuntimeError("this Launcher is already up")
        self._thread = threading.Thread(target=self._run_loop, name=f"zendock-{self.project}", daemon=True)
        self._thread.start()
        atexit.register(self.down)  # a forgotten down() must not leave processes behind the interpreter
        if not self._ready.wait(timeout_s):
            raise TimeoutError("the supervisor did not start")
        if self._error is not None:
            self._thread.join(timeout_s)
            raise self._error
        return self

    def _run_loop(self) -> None:
        loop = asyncio.new_event_loop()
        self._loop = loop
        try:
            loop.run_until_complete(self._main())
        except BaseException as exc:  # reported to up() when it happens before the stack is up
            self._error = exc
        finally:
            self._ready.set()
            loop.run_until_complete(loop.shutdown_asyncgens())
            loop.run_until_complete(loop.shutdown_default_executor())
            loop.close()

    async def _main(self) -> None:
        on_line = self._printer.line if self._printer is not None else None
        self._host = SupervisorHost(
            self.plan, self.services, self.paths, mode="api", backoff=self._backoff, on_line=on_line
        )
        run = asyncio.ensure_future(self._host.run())
        ready = asyncio.ensure_future(self._host.ready.wait())
        await asyncio.wait([run, ready], return_when=asyncio.FIRST_COMPLETED)
        self._ready.set()
        ready.cancel()
        self.exit_code = await run

    def down(self, timeout_s: float = 60.0) -> None:
        """Stop every service (dependents first, each within its grace period) and the supervisor."""
        thread, host, loop = self._thread, self._host, self._loop
        if thread is None:
            return
        atexit.unregister(self.down)
        if thread.is_alive() and host is not None and loop is not None and not loop.is_closed():
            try:
                asyncio.run_coroutine_threadsafe(host.down(), loop).result(timeout_s)
            except RuntimeError:  # the loop stopped meanwhile
                pass
            except TimeoutError:
                raise TimeoutError(
                    f"the stack {self.project} did not stop within {timeout_s}s: {self._still_active()}"
                ) from None
        thread.join(timeout_s)
        if thread.is_alive():
            raise TimeoutError(f"the supervisor of {self.project} did not stop within {timeout_s}s")

    def _still_active(self) -> str:
        """What a stuck ``down`` is waiting for: the services that have not ended, with their state."""

        async def statuses_now() -> list[ServiceStatus]:
            return self._supervisor().statuses()

        try:
            statuses = self._call(statuses_now, timeout_s=5.0)
        except Exception as exc:  # the loop is stuck too
            return f"(statuses unavailable: {exc!r})"
        active = [f"{s.name}={s.state}" for s in statuses if s.state not in ("exited", "stopped")]
        return ", ".join(active) or "every service ended; the supervisor itself is closing"

    # -- calls into the supervisor's loop ---------------------------------------------------------------
    def _call(self, make: Callable[[], Coroutine[Any, Any, T]], timeout_s: float | None = 60.0) -> T:
        if self._loop is None or self._host is None or self._thread is None or not self._thread.is_alive():
            raise RuntimeError(f"the stack {self.project} is not up")
        return asyncio.run_coroutine_threadsafe(make(), self._loop).result(timeout_s)

    def _supervisor(self) -> Supervisor:
        assert self._host is not None and self._host.supervisor is not None
        return self._host.supervisor

    def ps(self) -> list[ServiceStatus]:
        """Every started service's status, in start order."""

        async def statuses() -> list[ServiceStatus]:
            return self._supervisor().statuses()

        return self._call(statuses)

    def status(self, name: str) -> ServiceStatus:
        for status in self.ps():
            if status.name == name:
                return status
        raise KeyError(f"no such service started: {name}")

    def start(self, *names: str, timeout_s: float = 30.0) -> None:
        """Start services (and dependencies not running); returns once they run or ended, or after ``timeout_s``."""

        async def start() -> None:
            order = self._supervisor().start(list(names))
            await self._supervisor().wait_started(order, timeout_s)

        self._call(start)

    def stop(self, *names: str) -> None:
        """Stop services (SIGINT, SIGTERM, SIGKILL over each grace period); they are not restarted."""
        self._call(lambda: self._supervisor().stop(list(names)))

    def restart(self, *names: str, timeout_s: float = 30.0) -> None:
        """Stop, then start again (re-checking dependencies); returns like :meth:`start`."""

        async def restart() -> None:
            await self._supervisor().restart(list(names))
            await self._supervisor().wait_started(list(names), timeout_s)

        self._call(restart)

    def kill(self, name: str, sig: int = signal.SIGKILL) -> None:
        """Signal a running service's process group (its restart policy then applies)."""

        async def kill() -> list[str]:
            return self._supervisor().kill([name], sig)

        if not self._call(kill):
            raise RuntimeError(f"{name} is not running")

    def logs(self, name: str, tail_lines: int | None = None) -> list[str]:
        """The lines a service printed (and the launcher's ``[zendock]`` events about it), from its log files."""
        return [line.text for line in tail(self.paths.logs_dir, name, tail_lines)]

    # -- waiting -----------------------------------------------------------------------------------------
    def wait_until(
        self,
        predicate: Callable[[dict[str, ServiceStatus]], bool],
        timeout_s: float = 30.0,
        what: str = "the condition",
    ) -> dict[str, ServiceStatus]:
        """Poll statuses (by name) until ``predicate`` holds; :class:`StackNotReady` after ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while True:
            statuses = {s.name: s for s in self.ps()}
            if predicate(statuses):
                return statuses
            if time.monotonic() >= deadline:
                raise StackNotReady(
                    f"{self.project}: timed out after {timeout_s}s waiting for {what}:\n{format_statuses(statuses.values())}"
                )
            time.sleep(0.05)

    def wait_healthy(
        self, timeout_s: float = 30.0, services: Sequence[str] | None = None
    ) -> dict[str, ServiceStatus]:
        """Until every (given) service is running and healthy, or a one-shot step exited 0."""
        names = list(services) if services is not None else self.services

        def ready(st: dict[str, ServiceStatus]) -> bool:
            failed = [name for name in names if name in st and failed_for_good(st[name])]
            if failed:
                raise ServiceFailed(
                    f"{self.project}: {', '.join(failed)} cannot start:\n{format_statuses(st.values())}",
                    "; ".join(self._failure_line(st[name]) for name in failed),
                )
            return all(name in st and is_ready(st[name]) for name in names)

        try:
            return self.wait_until(ready, timeout_s, f"{', '.join(names)} to be healthy")
        except ServiceFailed:
            raise
        except StackNotReady as exc:
            statuses = {s.name: s for s in self.ps()}
            late = [name for name in names if name not in statuses or not is_ready(statuses[name])]
            raise StackNotReady(
                str(exc), "; ".join(self._not_ready_line(name, timeout_s) for name in late)
            ) from None

    def _failure_line(self, status: ServiceStatus) -> str:
        """``router cannot start: tcp/127.0.0.1:7447 is in use: ...``: the service and the line that says why."""
        why = failure_line(self.logs(status.name, 200)) or status.detail
        return f"{status.name} cannot start: {why}"

    def _not_ready_line(self, name: str, timeout_s: float) -> str:
        """``docking not healthy after 90s (its last line: ...)``: often a replacement that never declared its
        node token, or one that crashed."""
        last = failure_line(self.logs(name, 200))
        return f"{name} not healthy after {timeout_s:g}s ({f'its last line: {last}' if last else 'it printed nothing'})"

    def wait_state(self, name: str, state: str, timeout_s: float = 30.0) -> ServiceStatus:
        """Until ``name`` is in ``state`` (running | restarting | exited | stopped)."""
        return self.wait_until(
            lambda st: name in st and st[name].state == state, timeout_s, f"{name} to be {state}"
        )[name]
