"""The conformance probe's rates on sim time: a span starts only once the sim clock has been heard.

A probe that timed its first sample on wall time (no clock heard yet) and the rest on sim time read a topic
publishing at 20 Hz as 0 Hz, and waited out its whole wall limit; that failed a conform run in CI.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from deploy.contracts.probe import Probe
from shared.messages import Clock, Time


class _Sample:
    def __init__(self, payload: bytes) -> None:
        self.payload = self
        self.encoding = "application/msgpack;rosgraph_msgs/msg/Clock"
        self._bytes = payload

    def to_bytes(self) -> bytes:
        return self._bytes


class _Subscriber:
    def __init__(self, bus: _Bus, key: str, callback: Callable[[Any], None]) -> None:
        self._bus, self.key, self.callback = bus, key, callback

    def undeclare(self) -> None:
        with self._bus.lock:
            self._bus.subscribers.remove(self)


class _Bus:
    """A stand-in session: subscribers by key, and a put that calls each in turn, as Zenoh's thread does."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.subscribers: list[_Subscriber] = []

    def declare_subscriber(self, key: str, callback: Callable[[Any], None]) -> _Subscriber:
        sub = _Subscriber(self, key, callback)
        with self.lock:
            self.subscribers.append(sub)
        return sub

    def put(self, key: str, payload: bytes) -> None:
        with self.lock:
            targets = [s for s in self.subscribers if s.key == key]
        for sub in targets:
            sub.callback(_Sample(payload))


def _clock(ns: int) -> bytes:
    return Clock(clock=Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)).encode()


def test_a_clock_heard_only_after_watching_began_still_gives_the_sim_rate() -> None:
    bus = _Bus()
    probe = Probe(bus, "r1")  # type: ignore[arg-type]
    # the probe's own clock subscriber is deaf for the first messages, as one whose route is not yet up is
    deaf = list(bus.subscribers)
    bus.subscribers.clear()
    stop = threading.Event()

    def simulator() -> None:
        ns, sent = 100_000_000_000, 0
        while not stop.is_set():
            bus.put("r1/clock", _clock(ns))
            sent += 1
            if sent == 5:
                with bus.lock:
                    bus.subscribers.extend(deaf)
            ns += 50_000_000  # 20 Hz of sim time, at 4x
            time.sleep(0.0125)

    thread = threading.Thread(target=simulator, daemon=True)
    thread.start()
    try:
        samples = probe.collect("r1/clock", Clock, span_s=2.0, sim=True, wall_limit_s=10.0)
    finally:
        stop.set()
        thread.join(timeout=2.0)
    rate = samples.rate_hz()
    assert rate is not None and abs(rate - 20.0) < 4.0, f"{samples.decoded} messages, rate {rate}"
