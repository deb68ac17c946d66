"""The supervisor: runs a launch plan's services on asyncio, in dependency order, restarting them per policy.

Each service has a lifecycle task: wait for its dependencies, start, wait for the exit, then either stay
down or restart after an exponential backoff, re-checking its dependencies first. Stopping never cancels a
lifecycle mid-spawn: it sets a flag, signals the process group and waits for the lifecycle to finish.
Every change wakes waiters (dependencies, ``wait_until``) and calls ``on_change`` (the state file writer).
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from deploy.launcher.graph import dependency_order, with_dependencies
from deploy.launcher.health import LivelinessWatcher, run_check
from deploy.launcher.logs import EVENT_PREFIX, RotatingLog, RunFailure
from deploy.launcher.plan import LaunchPlan, ServicePlan
from deploy.launcher.process import GroupProcess, ServiceProcess
from deploy.launcher.restart import FINAL_EXITS, Backoff
from deploy.launcher.robot_template import service_for
from deploy.launcher.status import Phase, ServiceStatus, dependency_failed_detail, public_state
from deploy.launcher.zygote import STANDBY_GRACE_S, Zygote
from shared.suggestions import no_such

WATCHER_CLOSE_S = 5.0

#: Exit code reported when a command cannot be started at all (as a shell reports "command not found").
SPAWN_FAILED_EXIT = 127


class DependencyFailed(Exception):
    """A dependency ended in a way that can never satisfy its condition."""


def missing_program_hint(program: str) -> str:
    """What to do about a program that is not there (the ROS 2 faces' interpreter: ``make ros2``)."""
    if ".venv-ros2" in program:
        return " (.venv-ros2 is missing: run make ros2)"
    return ""


#: Why a run ended is read from its last lines, this many of them (the launcher's events among them).
RUN_LINES_READ = 200


def _describe_exit(code: int) -> str:
    if code in FINAL_EXITS:
        return f"exited with code {code} ({FINAL_EXITS[code]}: not restarted)"
    return f"killed by signal {-code}" if code < 0 else f"exited with code {code}"


class ServiceRunner:
    """One service's lifecycle and its current status."""

    def __init__(self, plan: ServicePlan, supervisor: Supervisor) -> None:
        self.plan = plan
        self.name = plan.name
        self._sup = supervisor
        self.phase = Phase.STOPPED
        self.process: GroupProcess | None = None
        self.restarts = 0
        self.starts = 0
        self.exit_code: int | None = None
        self.detail = ""
        #: Why the last run ended: its exit and the line that says why (``ps`` shows it while restarting
        #: and once it runs again).
        self.last_exit = ""
        #: Why the current run ends, followed as its lines (and the launcher's events) come.
        self._run_failure = RunFailure(window_lines=RUN_LINES_READ)
        self.next_start_at: float | None = None
        self._launched_wall: float | None = None
        self._health = "none"
        #: Whether the current (or last) run of the process passed its healthcheck.
        self._healthy_this_run = False
        self._exec_health = "starting"
        self._token_seen = False
        self._stopping = False
        self._wake = asyncio.Event()
        self._task: asyncio.Task[None] | None = None
        self._health_tasks: list[asyncio.Task[None]] = []
        self._checks_stopped = False
        self._timers: list[asyncio.TimerHandle] = []
        self._log = RotatingLog(supervisor.log_dir / f"{plan.name}.log") if supervisor.log_dir else None
        #: The warm standby (:mod:`deploy.standby`) the next restart starts from, when the supervisor keeps one.
        self._standby: Zygote | None = None
        self._standby_task: asyncio.Task[None] | None = None

    # -- output -------------------------------------------------------------------------------------
    def output(self, text: str) -> None:
        self._run_failure.add(text)
        if self._log is not None:
            self._log.write(text)
        self._sup.emit_line(self.name, text)

    def event(self, text: str) -> None:
        self.output(f"{EVENT_PREFIX}{text}")

    def close_log(self) -> None:
        if self._log is not None:
            self._log.close()

    # -- status ---------------------------------------------------------------------------------------
    @property
    def active(self) -> bool:
        """The lifecycle is going (waiting, running or between restarts)."""
        return self._task is not None and not self._task.done()

    @property
    def health(self) -> str:
        return self._health

    def status(self) -> ServiceStatus:
        process = self.process if self.phase is Phase.RUNNING else None
        detail = self.detail
        if self.phase is Phase.RESTARTING and self.next_start_at is not None:
            detail = f"restarting in {max(0.0, self.next_start_at - time.monotonic()):.1f}s ({detail})"
        return ServiceStatus(
            name=self.name,
            state=public_state(self.phase, self.starts),
            pid=process.pid if process else None,
            restarts=self.restarts,
            health=self._health,
            phase=self.phase.value,
            exit_code=self.exit_code,
            detail=detail,
            starts=self.starts,
            uptime_s=round(time.monotonic() - process.started_at, 3) if process else None,
            started_at=self._launched_wall if process else None,
            pid_create_time=process.create_time if process else None,
            members=list(self.plan.members),
            namespace=self.plan.namespace,
            standby=self._standby_state(),
            last_exit=self.last_exit
            if self.restarts and self.phase in (Phase.RUNNING, Phase.RESTARTING)
            else "",
        )

    def _set_phase(self, phase: Phase, detail: str | None = None) -> None:
        self.phase = phase
        if detail is not None:
            self.detail = detail
        self.refresh_health(notify=False)
        self._sup.notify()

    # -- health -------------------------------------------------------------------------------------
    def _compute_health(self) -> str:
        check = self.plan.health
        process = self.process
        if check is None or process is None or self.phase is not Phase.RUNNING:
            return "none"
        verdicts = []
        if check.liveliness_key:
            since = self._sup.token_alive_since(check.liveliness_key)
            if since is not None and since >= process.started_at:
                self._token_seen = True
                verdicts.append("healthy")
            elif self._token_seen or time.monotonic() - process.started_at >= check.liveliness_timeout_s:
                verdicts.append("unhealthy")
            else:
                verdicts.append("starting")
        if check.test_argv:
            verdicts.append(self._exec_health)
        if "unhealthy" in verdicts:
            return "unhealthy"
        return "healthy" if all(v == "healthy" for v in verdicts) else "starting"

    def refresh_health(self, notify: bool = True) -> None:
        health = self._compute_health()
        if health == "healthy":
            self._healthy_this_run = True
            self._keep_standby()
        if health != self._health:
            previous, self._health = self._health, health
            reportable = (
                health in ("healthy", "unhealthy")
                or previous in ("healthy", "unhealthy")
                and health == "starting"
            )
            if reportable and not self._stopping:
                self.event(f"health: {health}")
            if notify:
                self._sup.notify()

    async def _exec_checks(self, process: GroupProcess) -> None:
        check = self.plan.health
        assert check is not None and check.test_argv is not None
        failures = 0
        while not self._checks_stopped:
            ok = await run_check(
                check.test_argv, cwd=self.plan.cwd, env=dict(self.plan.env), timeout_s=check.test_timeout_s
            )
            if (
                self._checks_stopped
            ):  # the stop's cancellation can be lost inside the check (3.11's wait_for did)
                return
            if ok:
                failures = 0
                self._exec_health = "healthy"
            elif time.monotonic() - process.started_at >= check.start_period_s:
                failures += 1
                if failures >= check.retries:
                    self._exec_health = "unhealthy"
            self.refresh_health()
            await asyncio.sleep(check.interval_s)

    def _start_health(self, process: GroupProcess) -> None:
        check = self.plan.health
        self._token_seen = False
        self._exec_health = "starting"
        self._checks_stopped = False
        if check is None:
            return
        if check.test_argv:
            self._health_tasks.append(asyncio.ensure_future(self._exec_checks(process)))
        if check.liveliness_key:
            loop = asyncio.get_running_loop()
            self._timers.append(loop.call_later(check.liveliness_timeout_s + 0.01, self.refresh_health))

    async def _stop_health(self) -> None:
        self._checks_stopped = True
        for timer in self._timers:
            timer.cancel()
        tasks, self._health_tasks, self._timers = self._health_tasks, [], []
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task

    # -- warm standby ---------------------------------------------------------------------------------
    @property
    def _wants_standby(self) -> bool:
        return (
            self._sup.plan.standby
            and self.plan.standby_argv is not None
            and self.plan.restart.mode != "no"
            and not self._stopping
        )

    def _standby_state(self) -> str:
        standby = self._standby
        if standby is None or not standby.alive:
            return ""
        return "ready" if standby.ready else "importing"

    def _keep_standby(self) -> None:
        """Start a standby unless one is there or on its way: beside the service's first start (a standby
        still importing when the service dies makes that restart wait for the rest of its imports), and
        again when the service is healthy if the standby has died since."""
        if not self._wants_standby or self._standby_task is not None and not self._standby_task.done():
            return
        if self._standby is not None and self._standby.alive:
            return
        self._standby_task = asyncio.ensure_future(self._spawn_standby())

    async def _spawn_standby(self) -> None:
        assert self.plan.standby_argv is not None
        if self._standby is not None:  # one that has died since: let it go first
            gone, self._standby = self._standby, None
            self.event(f"warm standby gone ({_describe_exit(await gone.close())}): starting another")
        try:
            standby = await Zygote.spawn(
                self.plan.standby_argv,
                cwd=self.plan.cwd,
                env=self.plan.env,
                on_line=self.output,
                on_ready=self._sup.notify,
            )
        except OSError as exc:
            self.event(f"no warm standby: {exc.strerror or exc}")
            return
        self._standby = standby
        self._sup.notify()
        if self._stopping:  # stopped while it spawned: the lifecycle's end waits for it to go
            standby.process.stop(STANDBY_GRACE_S)

    async def _take_standby(self) -> GroupProcess | None:
        """The service, forked by the standby; None when there is no standby able to (a cold start then)."""
        if self._standby_task is not None:
            await asyncio.shield(self._standby_task)  # a spawn under way: its process is nearly there
        standby = self._standby
        if standby is None:
            return None
        child = await standby.fork()
        if child is None:
            self._standby = None
            self.event(f"warm standby gone ({_describe_exit(await standby.close())}): starting afresh")
        return child

    async def _drop_standby(self) -> None:
        """End the standby, if any, and wait until it is gone (it exits at once: it holds no session)."""
        if self._standby_task is not None and not self._standby_task.done():
            await asyncio.shield(self._standby_task)
        standby, self._standby = self._standby, None
        if standby is not None:
            await standby.close()

    # -- lifecycle ------------------------------------------------------------------------------------
    def start(self) -> None:
        """Start the lifecycle unless it is already going."""
        if self.active:
            return
        self._stopping = False
        self._wake = asyncio.Event()
        self._task = asyncio.ensure_future(self._lifecycle())

    async def stop(self) -> None:
        """Stop the service (never restarted afterwards) and wait until its process group is gone."""
        if not self.active:
            return
        self._stopping = True
        self._wake.set()
        if self.process is not None and self.process.returncode is None:
            self.event(f"stopping (grace period {self.plan.stop_grace_s:g}s)")
            self.process.stop(self.plan.stop_grace_s)
        self._sup.notify()
        assert self._task is not None
        await asyncio.shield(self._task)

    def send_signal(self, sig: int) -> bool:
        if self.process is None or self.process.returncode is not None:
            return False
        self.process.send_signal(sig)
        return True

    async def kill_now(self) -> None:
        if self.process is not None:
            await self.process.kill_now()
        if self._standby is not None:
            await self._standby.kill_now()

    async def _lifecycle(self) -> None:
        try:
            await self._run_until_done()
        except DependencyFailed as exc:
            self.event(f"not started: {exc}")
            self._set_phase(Phase.EXITED, str(exc))
        except Exception as exc:  # a supervisor bug must not leave a process unattended
            self.event(f"supervisor error: {exc!r}")
            if self.process is not None:
                await self.process.kill_now()
            self._set_phase(Phase.EXITED, f"supervisor error: {exc!r}")
        finally:
            await self._stop_health()
            self.process = None
            await self._drop_standby()

    async def _run_until_done(self) -> None:
        backoff = self._sup.backoff
        streak = 0
        last_restart_at: float | None = None
        while not self._stopping:
            self._set_phase(Phase.WAITING, "")
            if not await self._wait_for_dependencies():
                break
            launched_at = time.monotonic()
            self._launched_wall = time.time()
            self._run_failure.clear()  # why this run ends is this run's to say
            code = await self._run_once(launched_at)
            self.exit_code = code
            why = self._run_failure.reason()
            self.last_exit = _describe_exit(code) + (f": {why}" if why else "")
            if self._stopping:
                break
            run_was_healthy = self._healthy_this_run
            if run_was_healthy or time.monotonic() - launched_at >= backoff.reset_after_s:
                # A run that passed its healthcheck was not a crash at start-up, whatever ended it (a kill,
                # a fault minutes in): the backoff guards against start-up crash loops, and a healthy
                # service killed twice within reset_after_s would otherwise wait 0.2, 0.4, 0.8 ... s.
                streak = 0
            if not self.plan.restart.should_restart(code, streak):
                self._set_phase(Phase.EXITED, self.last_exit)
                return
            now = time.monotonic()
            delay_s = backoff.restart_delay_s(
                streak,
                run_was_healthy=run_was_healthy,
                since_last_restart_s=None if last_restart_at is None else now - last_restart_at,
            )
            last_restart_at = now
            streak += 1
            self.restarts += 1
            self.next_start_at = time.monotonic() + delay_s
            self.event(f"restarting in {delay_s:.1f}s (restart {self.restarts}, policy {self.plan.restart})")
            self._set_phase(Phase.RESTARTING, self.last_exit)
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(delay_s):
                    await self._wake.wait()
            self.next_start_at = None
        self._set_phase(
            Phase.STOPPED,
            f"stopped ({_describe_exit(self.exit_code)})" if self.exit_code is not None else "stopped",
        )
        self.event("stopped")

    async def _run_once(self, launched_at: float) -> int:
        process: GroupProcess | None = await self._take_standby() if self.starts else None
        how = "from its warm standby" if process is not None else ""
        if process is None:
            try:
                process = await ServiceProcess.spawn(
                    self.plan.argv, cwd=self.plan.cwd, env=self.plan.env, on_line=self.output
                )
            except OSError as exc:
                self.event(
                    f"cannot start {self.plan.argv[0]}: {exc.strerror or exc}{missing_program_hint(self.plan.argv[0])}"
                )
                return SPAWN_FAILED_EXIT
        process.started_at = launched_at
        self._healthy_this_run = False
        self.process = process
        self.starts += 1
        self.exit_code = None
        self.event(f"started (pid {process.pid}{', ' + how if how else ''})")
        self._keep_standby()
        self._start_health(process)
        self._set_phase(Phase.RUNNING, "")
        if self._stopping:
            process.stop(self.plan.stop_grace_s)
        code = await process.wait()
        await self._stop_health()
        self.event(_describe_exit(code))
        self.process = None
        self.refresh_health(notify=False)
        return code

    async def _wait_for_dependencies(self) -> bool:
        """True once every dependency's condition holds; False if stopped meanwhile."""
        while not self._stopping:
            waiting_for = []
            for dependency, condition in self.plan.depends_on.items():
                verdict = self._sup.dependency_verdict(dependency, condition)
                if verdict is not None:
                    waiting_for.append(verdict)
            if not waiting_for:
                return True
            self.detail = "waiting for " + ", ".join(waiting_for)
            await self._sup.changed()
        return False


class Supervisor:
    """Runs the services of a :class:`LaunchPlan`. Create and use it inside a running event loop."""

    def __init__(
        self,
        plan: LaunchPlan,
        *,
        backoff: Backoff | None = None,
        log_dir: Path | None = None,
        on_line: Callable[[str, str], None] | None = None,
        on_change: Callable[[], None] | None = None,
    ) -> None:
        self.plan = plan
        self.backoff = backoff or Backoff()
        self.log_dir = log_dir
        self.runners: dict[str, ServiceRunner] = {}
        self._on_line = on_line
        self._on_change = on_change
        self._changed = asyncio.Event()
        self._watcher: LivelinessWatcher | None = None
        self._dependents = {
            name: [n for n, p in plan.services.items() if name in p.depends_on] for name in plan.services
        }

    # -- plumbing ------------------------------------------------------------------------------------
    def emit_line(self, service: str, text: str) -> None:
        if self._on_line is not None:
            self._on_line(service, text)

    def notify(self) -> None:
        self._changed.set()
        self._changed = asyncio.Event()
        if self._on_change is not None:
            self._on_change()

    async def changed(self) -> None:
        """Return at the next change of any service's phase or health."""
        await self._changed.wait()

    def token_alive_since(self, key: str) -> float | None:
        return self._watcher.alive_since(key) if self._watcher is not None else None

    def _on_tokens(self) -> None:
        for runner in self.runners.values():
            runner.refresh_health(notify=False)
        self.notify()

    def open(self) -> None:
        """Start the liveliness watcher when some service's health depends on a token."""
        if self.plan.liveliness_needed and self._watcher is None:
            self._watcher = LivelinessWatcher(
                self.plan.connect,
                asyncio.get_running_loop(),
                self._on_tokens,
                config_file=self.plan.zenoh_config,
            )
            self._watcher.start()

    async def close(self) -> None:
        """Stop every service, then close the watcher's session and the log files."""
        await self.stop(list(self.runners))
        if self._watcher is not None:
            watcher, self._watcher = self._watcher, None
            closed = await asyncio.get_running_loop().run_in_executor(
                None, watcher.close_within, WATCHER_CLOSE_S
            )
            if not closed:
                self.emit_line(
                    "zendock",
                    f"the liveliness watcher's session did not close within {WATCHER_CLOSE_S:g}s; left to close",
                )
        for runner in self.runners.values():
            runner.close_log()

    # -- dependencies ---------------------------------------------------------------------------------
    def dependency_verdict(self, dependency: str, condition: str) -> str | None:
        """None when ``condition`` on ``dependency`` holds; otherwise what is awaited.

        Raises :class:`DependencyFailed` when the dependency ended in a way that cannot satisfy it.
        """
        runner = self.runners.get(dependency)
        if runner is None:
            return f"{dependency} ({condition}, not started)"
        ended = runner.phase is Phase.EXITED
        code = runner.exit_code
        if condition == "service_started":
            if runner.phase is Phase.RUNNING or (ended and code == 0):
                return None
        elif condition == "service_healthy":
            if runner.phase is Phase.RUNNING and runner.health == "healthy":
                return None
        elif condition == "service_completed_successfully":
            if ended and code == 0 and runner.starts:
                return None
        if ended:
            raise DependencyFailed(dependency_failed_detail(dependency, runner.detail or "exited", condition))
        return f"{dependency} ({condition})"

    def with_dependencies(self, names: Iterable[str]) -> list[str]:
        deps = {name: list(plan.depends_on) for name, plan in self.plan.services.items()}
        selected = with_dependencies(names, deps)
        return [name for name in dependency_order(deps) if name in selected]

    def stop_order(self, names: Iterable[str]) -> list[str]:
        """``names`` in the order :meth:`stop` ends them: each service before those it depends on, so the
        router every service connects through comes last."""
        wanted = set(names)
        return [name for name in reversed(self.with_dependencies(wanted)) if name in wanted]

    def _check_names(self, names: Iterable[str]) -> list[str]:
        """The services named (``r2/planner`` is a robot template's ``planner_r2``); KeyError for others."""
        services = list(self.plan.services)
        names = [service_for(name, services) for name in names]
        unknown = [name for name in names if name not in self.plan.services]
        if unknown:
            raise KeyError(no_such("service", unknown, services))
        return names

    # -- control --------------------------------------------------------------------------------------
    def start(self, names: Sequence[str]) -> list[str]:
        """Start services, and the dependencies of theirs that were never started; returns what was started.

        A dependency that was stopped on purpose stays stopped: the service waits for it (``ps`` says so).
        """
        names = self._check_names(names)
        order = [n for n in self.with_dependencies(names) if n in names or n not in self.runners]
        for name in order:
            runner = self.runners.get(name)
            if runner is None:
                runner = self.runners[name] = ServiceRunner(self.plan.services[name], self)
            runner.start()
        self.notify()
        return order

    async def stop(self, names: Sequence[str]) -> None:
        """Stop services, each after the services among ``names`` that depend on it."""
        names = [name for name in self._check_names(names) if name in self.runners]
        done = {name: asyncio.Event() for name in names}

        async def stop_one(name: str) -> None:
            for dependent in self._dependents.get(name, []):
                if dependent in done:
                    await done[dependent].wait()
            try:
                await self.runners[name].stop()
            finally:
                done[name].set()

        await asyncio.gather(*(stop_one(name) for name in names))

    async def restart(self, names: Sequence[str]) -> None:
        """Stop, then start again; the start re-checks dependencies as any start does."""
        names = self._check_names(names)
        await self.stop(names)
        self.start(names)

    def kill(self, names: Sequence[str], sig: int) -> list[str]:
        """Signal the process groups of running services; returns the ones signalled."""
        return [
            name
            for name in self._check_names(names)
            if name in self.runners and self.runners[name].send_signal(sig)
        ]

    async def wait_started(self, names: Sequence[str], timeout_s: float) -> bool:
        """Until each service has been started (or ended: it exited, its dependencies failed)."""

        def started() -> bool:
            return all(
                name in self.runners
                and (
                    self.runners[name].phase in (Phase.RUNNING, Phase.RESTARTING)
                    or not self.runners[name].active
                )
                for name in names
            )

        return await self.wait_until(started, timeout_s)

    async def kill_all_now(self) -> None:
        for runner in self.runners.values():
            await runner.kill_now()

    def statuses(self) -> list[ServiceStatus]:
        return [runner.status() for runner in self.runners.values()]

    def settled(self) -> bool:
        """No lifecycle is going: every service has exited or been stopped."""
        return all(not runner.active for runner in self.runners.values())

    async def wait_until(self, predicate: Callable[[], bool], timeout_s: float | None) -> bool:
        """Wait until ``predicate()`` holds after some change; False on timeout."""
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while not predicate():
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                return False
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(None if remaining is None else min(remaining, 0.5)):
                    await self.changed()
        return True
