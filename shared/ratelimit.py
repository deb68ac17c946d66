"""Logging that says a thing once per interval per key, so a flood of bad input yields one line."""

from __future__ import annotations

import logging
import threading
import time
from typing import Any


class RateLimitedLogger:
    """``warning(key, fmt, *args)`` logs at most once per ``interval_s`` for each ``key``.

    The line after a quiet spell says how many were suppressed, so nothing is silently lost.
    """

    def __init__(self, logger: logging.Logger, interval_s: float = 5.0) -> None:
        self._logger = logger
        self._interval_s = interval_s
        self._last: dict[str, float] = {}
        self._suppressed: dict[str, int] = {}
        self._lock = threading.Lock()

    def log(self, level: int, key: str, fmt: str, *args: Any) -> bool:
        now = time.monotonic()
        with self._lock:
            last = self._last.get(key)
            if last is not None and now - last < self._interval_s:
                self._suppressed[key] = self._suppressed.get(key, 0) + 1
                return False
            self._last[key] = now
            suppressed = self._suppressed.pop(key, 0)
        if suppressed:
            fmt = fmt + " (%d similar suppressed)"
            args = (*args, suppressed)
        self._logger.log(level, fmt, *args)
        return True

    def info(self, key: str, fmt: str, *args: Any) -> bool:
        return self.log(logging.INFO, key, fmt, *args)

    def warning(self, key: str, fmt: str, *args: Any) -> bool:
        return self.log(logging.WARNING, key, fmt, *args)

    def error(self, key: str, fmt: str, *args: Any) -> bool:
        return self.log(logging.ERROR, key, fmt, *args)
