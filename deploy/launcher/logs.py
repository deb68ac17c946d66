"""Per-service log files on disk: timestamped lines, rotated by size, read back by ``zendock logs``.

Each line is ``<UTC timestamp> <text>``; the timestamp lets ``logs`` interleave several services in the
order things happened. ``name.log`` is the newest file, then ``name.log.1`` ... ``name.log.<backups>``.
"""

from __future__ import annotations

import logging
import os
import re
import time
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import UTC, datetime
from logging.handlers import RotatingFileHandler
from pathlib import Path
from typing import TextIO

DEFAULT_MAX_BYTES = 5 * 1024 * 1024
DEFAULT_BACKUPS = 3
_LINE_RE = re.compile(r"^(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z) (.*)$")


def utc_stamp(epoch_s: float | None = None) -> str:
    moment = datetime.fromtimestamp(time.time() if epoch_s is None else epoch_s, tz=UTC)
    return moment.strftime("%Y-%m-%dT%H:%M:%S.") + f"{moment.microsecond // 1000:03d}Z"


class _UtcStampFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        return f"{utc_stamp(record.created)} {record.getMessage()}"


class RotatingLog:
    """Append-only line log that rolls over to ``.1`` before a line would take it past ``max_bytes``.

    The standard library's :class:`~logging.handlers.RotatingFileHandler` does the writing and the
    rollover (thread-safe, flushed after every line), used directly, outside the ``logging`` hierarchy, so
    a service's output never reaches another handler. As there, ``backups=0`` never rolls over.
    """

    def __init__(
        self, path: Path, max_bytes: int = DEFAULT_MAX_BYTES, backups: int = DEFAULT_BACKUPS
    ) -> None:
        self.path = path
        self.max_bytes = max_bytes
        self.backups = backups
        path.parent.mkdir(parents=True, exist_ok=True)
        self._handler = RotatingFileHandler(path, maxBytes=max_bytes, backupCount=backups, encoding="utf-8")
        self._handler.setFormatter(_UtcStampFormatter())

    def rotate(self) -> None:
        """Shift ``name.log`` to ``name.log.1`` (and so on), dropping the oldest, and start a new file."""
        with self._handler.lock:  # type: ignore[union-attr]
            self._handler.doRollover()

    def write(self, text: str) -> None:
        self._handler.handle(logging.makeLogRecord({"msg": text, "args": None}))

    def close(self) -> None:
        self._handler.close()


@dataclass(frozen=True)
class LogLine:
    service: str
    stamp: str
    text: str


def parse_line(service: str, raw: str) -> LogLine:
    match = _LINE_RE.match(raw)
    if match is None:
        return LogLine(service, "", raw)
    return LogLine(service, match.group(1), match.group(2))


def log_files(log_dir: Path, service: str) -> list[Path]:
    """Oldest first."""
    base = log_dir / f"{service}.log"
    rotated = sorted(
        (p for p in log_dir.glob(f"{service}.log.*") if p.suffix[1:].isdigit()),
        key=lambda p: int(p.suffix[1:]),
        reverse=True,
    )
    return [*rotated, *([base] if base.exists() else [])]


def tail(log_dir: Path, service: str, count: int | None) -> list[LogLine]:
    """The last ``count`` lines of a service (all when ``None``), across rotated files."""
    lines: deque[LogLine] = deque(maxlen=count) if count is not None else deque()
    if count == 0:
        return []
    for path in log_files(log_dir, service):
        with path.open(encoding="utf-8", errors="replace") as handle:
            for raw in handle:
                lines.append(parse_line(service, raw.rstrip("\n")))
    return list(lines)


#: The launcher's own lines in a service's log (``[zendock] started (pid 12)``), as the supervisor writes them.
EVENT_PREFIX = "[zendock] "
_ERROR_RE = re.compile(r"\berror\b", re.IGNORECASE)


class RunFailure:
    """Why a service's run failed, read line by line as the run prints: :func:`failure_line`'s answer over
    the run's last ``window_lines`` lines (all of them when None), in memory that does not grow with them.

    The supervisor feeds it every line of the current run. It keeps the last line, where the last traceback
    began, and the lines that say ``error`` still inside the window (a healthy service prints none), so a
    service that prints for hours costs the launcher a few lines, not a tail of hundreds. A
    ``[zendock] started`` event begins a new run's account; the launcher's ``cannot start`` line is kept
    across runs, as :func:`failure_line` keeps it.
    """

    __slots__ = (
        "_count",
        "_errors",
        "_last",
        "_last_at",
        "_spawn",
        "_spawn_at",
        "_traceback_at",
        "window_lines",
    )

    def __init__(self, window_lines: int | None = None) -> None:
        self.window_lines = window_lines
        self.clear()

    def clear(self) -> None:
        """Forget everything: a new run starts its own account."""
        self._spawn: str | None = None
        self._spawn_at = 0
        self._count = 0
        self._begin_run()

    def _begin_run(self) -> None:
        self._last: str | None = None
        self._last_at = 0
        self._traceback_at = 0
        self._errors: deque[tuple[int, str]] = deque()

    def add(self, text: str) -> None:
        self._count += 1
        if text.startswith(EVENT_PREFIX):
            if text.startswith(f"{EVENT_PREFIX}started"):
                self._begin_run()
            elif text.startswith(f"{EVENT_PREFIX}cannot start"):
                self._spawn, self._spawn_at = text, self._count
            return
        stripped = text.strip()
        if not stripped:
            return
        self._last, self._last_at = stripped, self._count
        if text.startswith("Traceback"):
            self._traceback_at = self._count
        if _ERROR_RE.search(text):
            self._errors.append((self._count, stripped))
            self._forget_before_window()

    def _forget_before_window(self) -> int:
        """Drop the error lines that have left the window; the number of the window's first line."""
        first = 1 if self.window_lines is None else self._count - self.window_lines + 1
        while self._errors and self._errors[0][0] < first:
            self._errors.popleft()
        return first

    def reason(self) -> str | None:
        first = self._forget_before_window()
        if self._last is None or self._last_at < first:
            # It never ran: the launcher's own line says why (``cannot start .venv-ros2/bin/python: ...``).
            spawn = self._spawn if self._spawn_at >= first else None
            return spawn.removeprefix(EVENT_PREFIX).strip() if spawn else None
        if self._traceback_at and self._traceback_at >= first:
            return self._last
        return self._errors[0][1] if self._errors else self._last


def failure_line(lines: list[str]) -> str | None:
    """The line that says why a service's last run failed, from its log's texts (oldest first).

    Only the last run counts (after the last ``[zendock] started`` event). A traceback's cause is its
    last line; otherwise the first line that says ``error`` (``... : error: world.yaml: cannot read ...``);
    else the last line the service printed; for a program that could not be started at all, the launcher's
    line saying why. None when there is nothing.
    """
    failure = RunFailure()
    for text in lines:
        failure.add(text)
    return failure.reason()


def merge_by_time(per_service: list[list[LogLine]]) -> list[LogLine]:
    """Interleave several services' lines by timestamp (stable within a service)."""
    tagged = [
        (line.stamp, index, order, line)
        for index, lines in enumerate(per_service)
        for order, line in enumerate(lines)
    ]
    return [item[3] for item in sorted(tagged, key=lambda item: (item[0], item[1], item[2]))]


class Follower:
    """New lines of one service's log as they are written, surviving rotation (the file is re-opened)."""

    def __init__(self, log_dir: Path, service: str) -> None:
        self.path = log_dir / f"{service}.log"
        self.service = service
        self._handle: TextIO | None = None
        self._inode: int | None = None
        self._partial = ""
        self._open(at_end=True)

    def _open(self, at_end: bool) -> None:
        try:
            handle = self.path.open(encoding="utf-8", errors="replace")
        except FileNotFoundError:
            return
        if at_end:
            handle.seek(0, os.SEEK_END)
        self._handle = handle
        self._inode = os.fstat(handle.fileno()).st_ino

    def poll(self) -> Iterator[LogLine]:
        if self._handle is None:
            self._open(at_end=False)
            if self._handle is None:
                return
        yield from self._drain()
        try:
            current = os.stat(self.path).st_ino
        except FileNotFoundError:
            return
        if current != self._inode:
            self._handle.close()
            self._handle = None
            self._open(at_end=False)
            yield from self._drain()

    def _drain(self) -> Iterator[LogLine]:
        assert self._handle is not None
        chunk = self._handle.read()
        if not chunk:
            return
        text = self._partial + chunk
        *complete, self._partial = text.split("\n")
        for raw in complete:
            yield parse_line(self.service, raw)

    def close(self) -> None:
        if self._handle is not None:
            self._handle.close()
