"""Subscriptions for the ``keys`` tools: raw samples with their arrival time, and the simulation clock.

Callbacks run on Zenoh's threads; :class:`KeyWatch` serialises them under one lock so the tools' windows
need no other locking. The tools declare no liveliness tokens: watching a key does not change what
``list`` and ``info`` report about it.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import zenoh

from shared.messages import Clock
from shared.names import topic_key
from shared.node import sequence_number
from shared.schema import MessageError
from shared.topics import CLOCK


@dataclass(frozen=True)
class ReceivedSample:
    """A sample as it arrived: its key, bytes, encoding text and the publisher's sequence number."""

    key: str
    payload: bytes
    encoding: str
    sequence: int | None
    wall_s: float  # time.time() at arrival
    monotonic_s: float  # time.monotonic() at arrival


def received(sample: zenoh.Sample) -> ReceivedSample:
    return ReceivedSample(
        key=str(sample.key_expr),
        payload=sample.payload.to_bytes(),
        encoding=str(sample.encoding) if sample.encoding is not None else "",
        sequence=sequence_number(sample.attachment),
        wall_s=time.time(),
        monotonic_s=time.monotonic(),
    )


class KeyWatch:
    """Subscribes to each key expression and hands ``(index, sample)`` to ``on_sample`` under :attr:`lock`."""

    def __init__(
        self, session: zenoh.Session, keys: Sequence[str], on_sample: Callable[[int, ReceivedSample], None]
    ) -> None:
        self.lock = threading.Lock()
        self._on_sample = on_sample
        self._subscribers = [
            session.declare_subscriber(key, self._callback(index)) for index, key in enumerate(keys)
        ]

    def _callback(self, index: int) -> Callable[[zenoh.Sample], None]:
        def deliver(sample: zenoh.Sample) -> None:
            if sample.kind != zenoh.SampleKind.PUT:
                return
            item = received(sample)
            with self.lock:
                self._on_sample(index, item)

        return deliver

    def close(self) -> None:
        for subscriber in self._subscribers:
            subscriber.undeclare()
        self._subscribers.clear()


class SimClock:
    """The latest time on the namespace's ``clock`` key; ``None`` until the first tick."""

    def __init__(self, session: zenoh.Session, namespace: str) -> None:
        self.key = topic_key(namespace, CLOCK)
        self._now_s: float | None = None
        self.rejected = 0
        self._subscriber = session.declare_subscriber(self.key, self._on_sample)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        try:
            self._now_s = Clock.decode(sample.payload.to_bytes()).clock.to_sec()
        except MessageError:
            self.rejected += 1

    def now(self) -> float | None:
        return self._now_s

    def close(self) -> None:
        self._subscriber.undeclare()
