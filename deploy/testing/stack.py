"""A test's own zendock stack: the default stack on a free loopback endpoint, in the test's temporary project
directory, up until the test ends, pass or fail.

It is what ``zendock demo`` brings up (:mod:`deploy.demo`), through the same launcher API: an embedded
router on a port nobody else uses, so tests never meet each other's robots, and ``.zendock/<project>/``
(state, logs) under the test's directory, so a failed test's logs are its own. A replaced service (a
user's program in place of one of zendock's, :mod:`deploy.replacements`) runs in the pytest root directory,
so ``python my_docking.py`` means the user's file; zendock's services run from zendock's root, as always.

Reading logs goes through the log files, not the supervisor, so a stack that is already down (a test whose
set-up failed) still shows them.
"""

from __future__ import annotations

import contextlib
from dataclasses import replace
from pathlib import Path

import psutil

from deploy.launcher import Launcher, StackNotReady, free_endpoint, is_ready, load_stack
from deploy.launcher.logs import failure_line, tail
from deploy.launcher.overrides import with_params
from deploy.launcher.stack_file import Stack
from deploy.launcher.status import ServiceStatus
from deploy.paths import REPO_ROOT
from deploy.replacements import apply_replacements
from deploy.testing.config import DEFAULT_STACK, StackConfig

#: The project name under ``.zendock/`` in the test's directory.
PROJECT = "zendock-test"


class StackUnhealthy(RuntimeError):
    """The stack did not become healthy in time; the message is one line naming the service and why."""


class LeftBehind(RuntimeError):
    """A service's process outlived the stack's ``down`` (the plugin killed it, and says which)."""


def run_replacements_in(before: Stack, after: Stack, directory: Path) -> Stack:
    """``after`` with every service whose command the replacements changed running in ``directory``."""
    services = dict(after.services)
    for name, spec in after.services.items():
        if spec.run != before.services[name].run:
            services[name] = replace(spec, working_dir=str(directory))
    return replace(after, services=services)


def log_texts(logs_dir: Path, service: str, lines: int | None) -> list[str]:
    return [line.text for line in tail(logs_dir, service, lines)]


def unhealthy_line(statuses: list[ServiceStatus], logs_dir: Path, timeout_s: float) -> str:
    """One line: the service that kept the stack from being healthy (one that failed before one that
    waits), its state, and the line of its log that says why (or its last line)."""
    waiting = [s for s in statuses if not is_ready(s)]
    if not waiting:
        return f"zendock stack not healthy within {timeout_s:g} s (every service is ready now)"
    failed = [s for s in waiting if s.restarts or s.state in ("exited", "restarting")]
    culprit = (failed or waiting)[0]
    why = failure_line(log_texts(logs_dir, culprit.name, 200)) or "it printed nothing"
    detail = f", {culprit.detail}" if culprit.detail else ""
    return (
        f"zendock stack not healthy within {timeout_s:g} s: {culprit.name} is {culprit.state} "
        f"(health {culprit.health}, restarts {culprit.restarts}{detail}); its log: {why}"
    )


def _alive(process: psutil.Process) -> bool:
    """Still the same process (not a reused pid), and not a zombie waiting to be reaped."""
    try:
        return process.is_running() and process.status() != psutil.STATUS_ZOMBIE
    except psutil.Error:
        return False


class ZendockStack:
    """The stack a test runs against: ``endpoint`` to connect to, ``launcher`` for ``ps``/``kill``/``restart``,
    ``logs(name)`` for what a service printed. Use as a context manager: up and healthy on entry, down on exit."""

    def __init__(self, config: StackConfig, project_dir: Path, rootdir: Path) -> None:
        self.config = config
        self.project_dir = project_dir
        self.endpoint = free_endpoint()
        project_dir.mkdir(parents=True, exist_ok=True)
        stack = load_stack(
            DEFAULT_STACK, env=config.environment(self.endpoint, project_dir), project_dir=REPO_ROOT
        )
        stack = with_params(stack, "docking", {"controller": config.controller})
        replaced = apply_replacements(stack, config.services)
        stack = run_replacements_in(stack, replaced, rootdir)
        self.launcher = Launcher(stack, project_dir=project_dir, working_dir=REPO_ROOT, project_name=PROJECT)
        self.services: list[str] = list(self.launcher.services)
        self.logs_dir = self.launcher.paths.logs_dir
        self._processes: list[psutil.Process] = []

    @property
    def namespace(self) -> str:
        return self.launcher.namespace

    def logs(self, service: str, tail_lines: int | None = None) -> list[str]:
        """The lines ``service`` printed (with the launcher's ``[zendock]`` events), oldest first."""
        return log_texts(self.logs_dir, service, tail_lines)

    def up(self) -> ZendockStack:
        """Start every service and wait until all are healthy; :class:`StackUnhealthy` (stack down) if not."""
        self.launcher.up()
        try:
            self.launcher.wait_healthy(timeout_s=self.config.healthy_timeout_s)
        except StackNotReady:
            line = unhealthy_line(self.launcher.ps(), self.logs_dir, self.config.healthy_timeout_s)
            self.down()
            raise StackUnhealthy(line) from None
        except BaseException:
            self.down()
            raise
        return self

    def down(self) -> None:
        """Stop everything; :class:`LeftBehind` if a service's process survived (it is killed first)."""
        with contextlib.suppress(RuntimeError):  # not up (any more): nothing to list
            for status in self.launcher.ps():
                if status.pid is not None:
                    with contextlib.suppress(psutil.Error):
                        self._processes.append(psutil.Process(status.pid))
        self.launcher.down()
        survivors = [p for p in self._processes if _alive(p)]
        self._processes = []
        if survivors:
            described = [f"{p.pid} {' '.join(p.cmdline())[:120]}" for p in survivors]
            for process in survivors:
                with contextlib.suppress(psutil.Error):
                    process.kill()
            raise LeftBehind(f"processes outlived the stack's down (killed now): {described}")

    def __enter__(self) -> ZendockStack:
        return self.up()

    def __exit__(self, *exc_info: object) -> None:
        self.down()
