"""What ``zendock conform`` sees of the bus: tokens, the graph, samples on sim time, raw requests.

It reads the wire as any other program would (raw Zenoh samples, decoded with the contract's types), so it
judges a replacement by what it puts on the bus, not by how it was written.
"""

from __future__ import annotations

import threading
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

import msgpack
import zenoh

from deploy.keys.graph import node_display_name, query_graph
from deploy.nodes import nodes_of
from shared.encoding import schema_of
from shared.frames import frame_name
from shared.messages import Clock
from shared.names import node_token_key, topic_key
from shared.schema import Message, MessageError

M = TypeVar("M", bound=Message)

#: Payloads no service may choke on: not msgpack, msgpack of the wrong shape, a map of unknown fields, nothing.
MALFORMED_PAYLOADS: tuple[bytes, ...] = (
    b"\xc1\xc1\xc1",
    msgpack.packb([1, 2, 3]),
    msgpack.packb({"nonsense": 1}),
    b"",
    msgpack.packb({"header": "not a header"}),
    b"\xff" * 64,
)


@dataclass
class Samples:
    """What arrived on one key while watched: counts on sim (or wall) time, decoding failures, encodings."""

    key: str
    received: int = 0
    decoded: int = 0
    failures: list[str] = field(default_factory=list)
    encodings: set[str] = field(default_factory=set)
    first_s: float | None = None
    last_s: float | None = None
    latest: Any = None
    #: ``(header.frame_id, child_frame_id)`` of the decoded messages that have a header, leading ``/`` dropped.
    frames: Counter[tuple[str, str]] = field(default_factory=Counter)
    #: When each decoded message happened, kept when asked (event topics: few messages): on sim time, its
    #: header's stamp where it has one (a burst that arrives together after the world was held for a late
    #: input happened over the sim time it was stamped with); otherwise its arrival (sim or wall).
    times: list[float] | None = None
    #: Every decoded message, kept when asked.
    messages: list[Any] | None = None

    def peak_per_s(self) -> int:
        """The most messages within any one second (of the clock they were timed on)."""
        times, most, first = sorted(self.times or []), 0, 0
        for last, t in enumerate(times):
            while t - times[first] >= 1.0:
                first += 1
            most = max(most, last - first + 1)
        return most

    def rate_hz(self) -> float | None:
        if self.first_s is None or self.last_s is None or self.last_s <= self.first_s or self.decoded < 2:
            return None
        return (self.decoded - 1) / (self.last_s - self.first_s)


class Probe:
    """A client session on the conform stack's router, with the sim clock when there is one."""

    def __init__(self, session: zenoh.Session, namespace: str) -> None:
        self.session = session
        self.namespace = namespace
        self._lock = threading.Lock()
        self._sim_s: float | None = None
        self._clock_sub = session.declare_subscriber(topic_key(namespace, "clock"), self._on_clock)

    def _on_clock(self, sample: zenoh.Sample) -> None:
        try:
            t = Clock.decode(sample.payload.to_bytes()).clock.to_sec()
        except MessageError:
            return
        with self._lock:
            self._sim_s = t

    def sim_now(self) -> float | None:
        with self._lock:
            return self._sim_s

    def wait_clock(self, timeout_s: float) -> bool:
        """Whether the sim clock has been heard, waiting up to ``timeout_s`` (wall) for its first message.

        Spans on sim time start only once it has: a span begun on wall time and ended on sim time would mix
        two clocks, and read as a clock that never advances."""
        deadline = time.monotonic() + timeout_s
        while self.sim_now() is None:
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)
        return True

    def pass_time(self, span_s: float, sim: bool, wall_limit_s: float) -> None:
        """Return once ``span_s`` seconds of sim (or wall) time have passed, or ``wall_limit_s`` of wall time;
        on sim time, counted from the clock's first message."""
        start_wall = time.monotonic()
        if sim:
            self.wait_clock(wall_limit_s)
        start = self.now(sim)
        while self.now(sim) - start < span_s and time.monotonic() - start_wall < wall_limit_s:
            time.sleep(0.05)

    def now(self, sim: bool) -> float:
        """Sim time when asked and a clock runs, else wall time (monotonic)."""
        if sim:
            t = self.sim_now()
            if t is not None:
                return t
        return time.monotonic()

    def key(self, name: str, namespace: str | None = None) -> str:
        return topic_key(self.namespace if namespace is None else namespace, name)

    # --- tokens and the graph --------------------------------------------------------------------------------

    def has_token(self, key_expr: str, timeout_s: float = 1.0) -> bool:
        replies = self.session.liveliness().get(key_expr, timeout=timeout_s)
        return any(reply.ok is not None for reply in replies)

    def wait_node(
        self, namespace: str, node: str, timeout_s: float, alive: Callable[[], bool]
    ) -> float | None:
        """Seconds until the node's ready token appears, or ``None`` (timeout, or ``alive()`` turned false)."""
        start = time.monotonic()
        key = node_token_key(namespace, node)
        while time.monotonic() - start < timeout_s:
            if self.has_token(key, 0.5):
                return time.monotonic() - start
            if not alive():
                return None
            time.sleep(0.1)
        return None

    def node_endpoints(self, namespace: str, node: str) -> set[tuple[str, str, str]]:
        """``(kind, key, type)`` of every endpoint token the node declared."""
        info = nodes_of(query_graph(self.session, timeout_s=2.0)).get(node_display_name(namespace, node))
        if info is None:
            return set()
        return {(kind, e.key, e.type_name) for kind, found in info.endpoints.items() for e in found}

    # --- samples ---------------------------------------------------------------------------------------------

    def watch(
        self, key: str, msg_type: type[M], sim: bool, keep_times: bool = False, keep_messages: bool = False
    ) -> tuple[Samples, Any]:
        """Start collecting ``key``; returns the live tally and the subscriber (undeclare it when done)."""
        tally = Samples(key, times=[] if keep_times else None, messages=[] if keep_messages else None)
        lock = threading.Lock()

        def on_sample(sample: zenoh.Sample) -> None:
            now = self.now(sim)
            with lock:
                tally.received += 1
                tally.encodings.add(str(sample.encoding))
                try:
                    msg = msg_type.decode(sample.payload.to_bytes())
                except MessageError as exc:
                    if len(tally.failures) < 3:
                        tally.failures.append(str(exc))
                    return
                tally.decoded += 1
                tally.latest = msg
                header = getattr(msg, "header", None)
                if header is not None:
                    child = getattr(msg, "child_frame_id", "")
                    tally.frames[(frame_name(header.frame_id), frame_name(child))] += 1
                if tally.first_s is None:
                    tally.first_s = now
                tally.last_s = now
                if tally.times is not None:
                    stamp = header.stamp.to_sec() if sim and header is not None else 0.0
                    tally.times.append(stamp if stamp > 0.0 else now)
                if tally.messages is not None:
                    tally.messages.append(msg)

        return tally, self.session.declare_subscriber(key, on_sample)

    def collect(
        self,
        key: str,
        msg_type: type[M],
        span_s: float,
        sim: bool,
        wall_limit_s: float,
        keep_messages: bool = False,
    ) -> Samples:
        """Samples on ``key`` over ``span_s`` seconds of sim (or wall) time, at most ``wall_limit_s`` wall."""
        start_wall = time.monotonic()
        if sim:
            self.wait_clock(wall_limit_s)
        tally, sub = self.watch(key, msg_type, sim, keep_messages=keep_messages)
        try:
            self.pass_time(span_s, sim, wall_limit_s - (time.monotonic() - start_wall))
        finally:
            sub.undeclare()
        return tally

    def wait_for(
        self, key: str, msg_type: type[M], predicate: Callable[[M], bool], timeout_s: float
    ) -> M | None:
        """The first message on ``key`` for which ``predicate`` holds, or ``None`` after ``timeout_s`` (wall)."""
        found: list[M] = []
        event = threading.Event()

        def on_sample(sample: zenoh.Sample) -> None:
            try:
                msg = msg_type.decode(sample.payload.to_bytes())
            except MessageError:
                return
            if not event.is_set() and predicate(msg):
                found.append(msg)
                event.set()

        sub = self.session.declare_subscriber(key, on_sample)
        try:
            event.wait(timeout_s)
        finally:
            sub.undeclare()
        return found[0] if found else None

    # --- raw requests and payloads ---------------------------------------------------------------------------

    def query_raw(self, key: str, payload: bytes, timeout_s: float = 3.0) -> tuple[str, str]:
        """``("error", text)``, ``("ok", encoding)`` or ``("silent", "")`` for a raw request."""
        for reply in self.session.get(
            key, payload=payload, timeout=timeout_s, target=zenoh.QueryTarget.BEST_MATCHING
        ):
            if reply.err is not None:
                return "error", reply.err.payload.to_bytes().decode("utf-8", "replace")[:200]
            if reply.ok is not None:
                return "ok", schema_of(reply.ok.encoding)[1]
        return "silent", ""

    def put_raw(self, key: str, payload: bytes) -> None:
        self.session.put(key, payload)

    def close(self) -> None:
        self._clock_sub.undeclare()
