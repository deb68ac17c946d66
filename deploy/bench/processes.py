"""Service processes for a benchmark: each in its own process group, its log in a directory."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

from deploy.paths import REPO_ROOT


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


class ServiceGroup:
    """``python -m services.<name> --connect <endpoint> --namespace <ns> <args>`` for each named service."""

    def __init__(self, endpoint: str, namespace: str, commands: dict[str, list[str]], log_dir: Path) -> None:
        common = ["--connect", endpoint, "--namespace", namespace]
        self.log_dir = log_dir
        self.procs: dict[str, subprocess.Popen[bytes]] = {}
        for name, args in commands.items():
            with open(log_dir / f"{name}.log", "wb") as log:
                self.procs[name] = subprocess.Popen(
                    [sys.executable, "-m", f"services.{name}", *common, *args],
                    cwd=REPO_ROOT,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,
                )

    def tails(self, lines: int = 15) -> str:
        """The last lines of every log, for an error message (the log directory is temporary)."""
        parts = []
        for name in self.procs:
            text = (self.log_dir / f"{name}.log").read_text(errors="replace").splitlines()[-lines:]
            parts.append(f"--- {name} ---\n" + "\n".join(text))
        return "\n".join(parts)

    def close(self) -> None:
        for proc in self.procs.values():
            for sig, wait_s in ((signal.SIGINT, 5.0), (signal.SIGKILL, 5.0)):
                if proc.poll() is not None:
                    break
                try:
                    os.killpg(proc.pid, sig)
                    proc.wait(wait_s)
                except (ProcessLookupError, subprocess.TimeoutExpired):
                    continue

    def __enter__(self) -> ServiceGroup:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
