"""The program under test in ``zendock conform``: started as the launcher starts a service, stopped by hand.

It gets what the launcher gives zendock's own service: the environment (``ZENDOCK_CONNECT``,
``ZENDOCK_NAMESPACE``) and zendock's flags appended to its command. It runs in a process group of its
own, so SIGTERM reaches a wrapper script's children too, and nothing outlives :meth:`Candidate.close`.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

#: The contract's limit: SIGTERM ends a service, exit code 0, within this.
SIGTERM_LIMIT_S = 2.0


class Candidate:
    """One program in place of a zendock service; its output goes to ``log_path``."""

    def __init__(self, argv: list[str], env: dict[str, str], log_path: Path, cwd: Path) -> None:
        self.argv = argv
        self.env = env
        self.log_path = log_path
        self.cwd = cwd
        self.proc: subprocess.Popen[bytes] | None = None
        self.starts = 0

    def start(self) -> None:
        self.log_path.parent.mkdir(parents=True, exist_ok=True)
        with self.log_path.open("ab") as log:
            log.write(f"--- start {self.starts + 1}: {' '.join(self.argv)}\n".encode())
            log.flush()
            self.proc = subprocess.Popen(
                self.argv,
                env=self.env,
                cwd=self.cwd,
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        self.starts += 1

    @property
    def running(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    @property
    def exit_code(self) -> int | None:
        return None if self.proc is None else self.proc.poll()

    def terminate(self, limit_s: float = SIGTERM_LIMIT_S) -> tuple[int | None, float]:
        """SIGTERM to the group; ``(exit code or None if still running after the limit, seconds it took)``."""
        assert self.proc is not None
        start = time.monotonic()
        self._signal(signal.SIGTERM)
        try:
            code: int | None = self.proc.wait(timeout=limit_s)
        except subprocess.TimeoutExpired:
            code = None
        return code, time.monotonic() - start

    def close(self) -> None:
        """Make sure nothing of it is left: SIGKILL to the whole group."""
        if self.proc is None:
            return
        self._signal(signal.SIGKILL)
        try:
            self.proc.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            pass

    def _signal(self, sig: int) -> None:
        assert self.proc is not None
        try:
            os.killpg(self.proc.pid, sig)
        except (ProcessLookupError, PermissionError):
            pass

    def last_lines(self, n: int = 5) -> list[str]:
        try:
            lines = self.log_path.read_text(encoding="utf-8", errors="replace").splitlines()
        except OSError:
            return []
        return [line for line in lines if line.strip()][-n:]
