"""Watching the bus from a test: typed waits that explain what did arrive when they time out."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any, Generic, TypeVar

import zenoh

from shared.schema import Message, MessageError

M = TypeVar("M", bound=Message)


class KeyRecorder(Generic[M]):
    """Subscribes to a key (wildcards allowed) and keeps what arrives, decoded and raw."""

    def __init__(self, session: zenoh.Session, key: str, msg_type: type[M], keep: int = 1000) -> None:
        self.key = key
        self.msg_type = msg_type
        self._keep = keep
        self._cv = threading.Condition()
        self.messages: list[M] = []
        self.keys: list[str] = []
        self.errors: list[str] = []
        self.count = 0
        self._sub = session.declare_subscriber(key, self._on_sample)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        try:
            msg = self.msg_type.decode(sample.payload.to_bytes())
        except MessageError as exc:
            with self._cv:
                self.errors.append(str(exc))
                self._cv.notify_all()
            return
        with self._cv:
            self.count += 1
            self.messages.append(msg)
            self.keys.append(str(sample.key_expr))
            if len(self.messages) > self._keep:
                del self.messages[: len(self.messages) - self._keep]
                del self.keys[: len(self.keys) - self._keep]
            self._cv.notify_all()

    def latest(self) -> M | None:
        with self._cv:
            return self.messages[-1] if self.messages else None

    def wait_for(
        self, predicate: Callable[[M], bool] = lambda _m: True, timeout_s: float = 10.0, after: int = 0
    ) -> M:
        """The first message (at or after index ``after`` of the ones seen) matching ``predicate``."""
        deadline = time.monotonic() + timeout_s
        checked = after
        with self._cv:
            while True:
                while checked < self.count:
                    index = checked - (self.count - len(self.messages))
                    checked += 1
                    if index >= 0 and predicate(self.messages[index]):
                        return self.messages[index]
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    break
                self._cv.wait(min(remaining, 0.2))
            raise AssertionError(
                self.describe(f"no matching {self.msg_type.TYPE_NAME} on {self.key} within {timeout_s:g} s")
            )

    def describe(self, headline: str) -> str:
        tail = [repr(m)[:300] for m in self.messages[-3:]]
        return (
            f"{headline}; received {self.count} valid message(s), {len(self.errors)} invalid"
            + (f"; last: {tail}" if tail else "")
            + (f"; last error: {self.errors[-1]}" if self.errors else "")
        )

    def close(self) -> None:
        self._sub.undeclare()


def wait_for_message(
    session: zenoh.Session,
    key: str,
    msg_type: type[M],
    predicate: Callable[[M], bool] = lambda _m: True,
    timeout_s: float = 10.0,
) -> M:
    """Wait for one message on ``key`` matching ``predicate``; fails showing what did arrive."""
    recorder = KeyRecorder(session, key, msg_type)
    try:
        return recorder.wait_for(predicate, timeout_s)
    finally:
        recorder.close()


def liveliness_keys(
    session: zenoh.Session, pattern: str = "@zendock/**", timeout_s: float = 1.0
) -> list[str]:
    return [
        str(r.ok.key_expr) for r in session.liveliness().get(pattern, timeout=timeout_s) if r.ok is not None
    ]


def drain(_: Any) -> None:
    """A no-op callback for subscribers kept only for their side effects."""
