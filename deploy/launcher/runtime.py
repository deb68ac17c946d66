"""The runtime directory of a project, ``.zendock/<project>/``, and talking to its supervisor.

Layout: ``supervisor.json`` (pid, socket, mode), ``state.json`` (every service's status, rewritten on each
change), ``control.sock`` (newline-delimited JSON requests), ``logs/<service>.log*`` and ``daemon.log``.
``down`` removes everything but the logs.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import signal
import socket
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import psutil

from deploy.launcher.process import live_group_members, signal_group
from deploy.launcher.status import ServiceStatus
from shared.files import write_atomically

RUNTIME_DIRNAME = ".zendock"
_MAX_SOCKET_PATH = 100  # sockaddr_un holds 108 bytes


class ControlError(RuntimeError):
    """The supervisor is not running, did not answer, or refused the request."""


class RequestRefused(ControlError):
    """The supervisor answered and refused the request (a service it does not run, a bad request)."""


@dataclass(frozen=True)
class RuntimePaths:
    state_dir: Path

    @classmethod
    def for_project(cls, project_dir: Path, project: str) -> RuntimePaths:
        return cls((project_dir / RUNTIME_DIRNAME / project).resolve())

    @property
    def supervisor_file(self) -> Path:
        return self.state_dir / "supervisor.json"

    @property
    def state_file(self) -> Path:
        return self.state_dir / "state.json"

    @property
    def logs_dir(self) -> Path:
        return self.state_dir / "logs"

    @property
    def previous_logs_dir(self) -> Path:
        return self.state_dir / "logs.previous"

    @property
    def daemon_log(self) -> Path:
        return self.state_dir / "daemon.log"

    @property
    def socket_path(self) -> Path:
        """``control.sock`` in the state directory, or a short path under the temp dir when that is too long."""
        natural = self.state_dir / "control.sock"
        if len(str(natural)) <= _MAX_SOCKET_PATH:
            return natural
        digest = hashlib.sha1(str(self.state_dir).encode()).hexdigest()[:16]
        return Path(tempfile.gettempdir()) / f"zendock-{os.getuid()}-{digest}.sock"


def write_json_atomic(path: Path, data: Any) -> None:
    write_atomically(path, json.dumps(data, indent=1).encode("utf-8"))


def read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def process_matches(pid: int | None, create_time: float | None) -> psutil.Process | None:
    """The live process with this pid and start time (not a recycled pid), if any."""
    if not pid:
        return None
    try:
        proc = psutil.Process(pid)
        if create_time is not None and abs(proc.create_time() - create_time) > 0.01:
            return None
        if proc.status() == psutil.STATUS_ZOMBIE:
            return None
        return proc
    except psutil.Error:
        return None


def supervisor_info(paths: RuntimePaths) -> dict[str, Any] | None:
    """The running supervisor's record, or None when there is none (or it died)."""
    info = read_json(paths.supervisor_file)
    if not isinstance(info, dict):
        return None
    if process_matches(info.get("pid"), info.get("create_time")) is None:
        return None
    return info


def recorded_statuses(paths: RuntimePaths) -> list[ServiceStatus]:
    data = read_json(paths.state_file)
    if not isinstance(data, dict):
        return []
    return [ServiceStatus.from_dict(item) for item in data.get("services", []) if isinstance(item, dict)]


def request(paths: RuntimePaths, op: str, *, timeout_s: float = 10.0, **fields: Any) -> dict[str, Any]:
    """Send one request to the project's supervisor and return its answer (``ok`` is true)."""
    if supervisor_info(paths) is None:
        raise ControlError(f"no supervisor is running for {paths.state_dir}")
    message = json.dumps({"op": op, **fields}).encode() + b"\n"
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as conn:
            conn.settimeout(timeout_s)
            conn.connect(str(paths.socket_path))
            conn.sendall(message)
            buffer = b""
            while not buffer.endswith(b"\n"):
                chunk = conn.recv(65536)
                if not chunk:
                    break
                buffer += chunk
    except OSError as exc:
        raise ControlError(f"the supervisor did not answer {op!r}: {exc}") from None
    try:
        reply = json.loads(buffer)
    except ValueError:
        raise ControlError(f"the supervisor gave no answer to {op!r}") from None
    if not isinstance(reply, dict) or not reply.get("ok"):
        error = reply.get("error", "request refused") if isinstance(reply, dict) else "not a JSON object"
        raise RequestRefused(str(error))
    return reply


def clear_runtime(paths: RuntimePaths) -> None:
    """Remove the runtime files, keeping the logs."""
    for path in (paths.supervisor_file, paths.state_file, paths.socket_path):
        with contextlib.suppress(FileNotFoundError):
            path.unlink()


def stop_orphans(paths: RuntimePaths, grace_s: float = 5.0) -> list[str]:
    """After a supervisor died: SIGTERM, then SIGKILL after ``grace_s``, the process groups it recorded
    whose leader is still the same process. Returns the names of the services found running, latest
    started first (the order a supervisor stops them in: the router they connect through last)."""
    groups = {}
    for status in recorded_statuses(paths):
        if status.pid is not None and process_matches(status.pid, status.pid_create_time) is not None:
            groups[status.name] = status.pid
    for pgid in groups.values():
        signal_group(pgid, signal.SIGTERM)
    deadline = time.monotonic() + grace_s
    while time.monotonic() < deadline and any(live_group_members(pgid) for pgid in groups.values()):
        time.sleep(0.05)
    for pgid in groups.values():
        if live_group_members(pgid):
            signal_group(pgid, signal.SIGKILL)
    return list(reversed(groups))


def start_new_logs(paths: RuntimePaths) -> None:
    """A new run gets fresh logs; the previous run's stay in ``logs.previous/`` (one run kept)."""
    if paths.logs_dir.is_dir():
        shutil.rmtree(paths.previous_logs_dir, ignore_errors=True)
        os.replace(paths.logs_dir, paths.previous_logs_dir)
    paths.logs_dir.mkdir(parents=True, exist_ok=True)
