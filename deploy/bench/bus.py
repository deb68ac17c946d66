"""Round-trip latency of zendock's typed publish/subscribe against raw zenoh-python, same run.

Both sides are separate processes on one loopback router. The typed path decodes and validates on
arrival, runs the callback under the node's executor rules and validates again on publishing (with
the encoding, sequence number and source info every zendock sample carries); the raw path passes
bytes through zenoh-python callbacks. Rounds alternate between the two in blocks so machine noise hits
both alike; the report gives medians and p99 of each and their ratio.

What makes the comparison fair: both sides use declared publishers with the same QoS and
subscriber callbacks; the payloads are the same 84-byte Twist; every block starts fresh processes and
sessions and discards its first rounds as warm-up; the blocks alternate typed-first and raw-first, so
a drift in machine load within a block does not always favour the same path. The messages (typed) and
payloads (raw) are built before the clock starts, as the raw payload always was: making a message is
the application's work, not the bus's, and timing it on one side only would charge it to the bus.
"""

from __future__ import annotations

import socket
import statistics
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from deploy.bench.echo import PING_KEY, PONG_KEY
from shared.messages import Twist
from shared.node import RELIABLE, Node
from shared.session import SessionSpec, open_session


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@dataclass
class BusBenchResult:
    rtt_p50_us: float
    rtt_p99_us: float
    raw_rtt_p50_us: float
    raw_rtt_p99_us: float
    rounds: int

    @property
    def ratio(self) -> float:
        return self.rtt_p50_us / self.raw_rtt_p50_us

    def as_dict(self) -> dict[str, float]:
        return {
            "rtt_p50_us": round(self.rtt_p50_us, 1),
            "rtt_p99_us": round(self.rtt_p99_us, 1),
            "raw_rtt_p50_us": round(self.raw_rtt_p50_us, 1),
            "raw_rtt_p99_us": round(self.raw_rtt_p99_us, 1),
            "ratio": round(self.ratio, 3),
            "rounds": self.rounds,
        }


def _percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


class _Echo:
    def __init__(self, mode: str, endpoint: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "deploy.bench.echo", mode, endpoint],
            stdout=subprocess.PIPE, text=True, start_new_session=True,
        )
        assert self.proc.stdout is not None
        if self.proc.stdout.readline().strip() != "ready":
            raise RuntimeError(f"bench echo ({mode}) failed to start")

    def close(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


WARMUP_ROUNDS = 50


def _twists(rounds: int) -> list[Twist]:
    """A different message every round (the same wire size: floats are always float64)."""
    return [Twist.planar(0.001 * i, 0.5) for i in range(rounds + WARMUP_ROUNDS)]


def _measure_typed(endpoint: str, rounds: int) -> list[float]:
    arrived = threading.Event()
    messages = _twists(rounds)
    with open_session(SessionSpec(connect=(endpoint,))) as session, Node("bench_ping", session) as node:
        ping = node.create_publisher(Twist, PING_KEY, RELIABLE)
        sub = node.create_subscription(Twist, PONG_KEY, lambda _m: arrived.set(), RELIABLE)
        spinner = threading.Thread(target=node.spin, daemon=True)
        spinner.start()
        samples = _ping_loop(ping.publish, messages, arrived)
        node.shutdown()
        spinner.join(2)
        sub.undeclare()
        ping.undeclare()
    return samples


def _measure_raw(endpoint: str, rounds: int) -> list[float]:
    arrived = threading.Event()
    payloads = [msg.encode() for msg in _twists(rounds)]
    with open_session(SessionSpec(connect=(endpoint,))) as session:
        pub = session.declare_publisher(PING_KEY)
        sub = session.declare_subscriber(PONG_KEY, lambda _s: arrived.set())
        samples = _ping_loop(pub.put, payloads, arrived)
        sub.undeclare()
        pub.undeclare()
    return samples


def _ping_loop(send: Callable[[Any], object], items: list[Any], arrived: threading.Event) -> list[float]:
    """Send each item, wait for its pong; round-trip times in us after the warm-up rounds.

    The echo is ready when its subscriber is declared, but the router may learn of it (or of ours) a
    little later on a loaded machine: the first ping is repeated until a pong shows the route is up.
    """
    deadline = time.monotonic() + 10.0
    while True:
        arrived.clear()
        send(items[0])
        if arrived.wait(0.25):
            break
        if time.monotonic() > deadline:
            raise RuntimeError("bench: the echo never answered")
    time.sleep(0.3)  # let any answer to a repeated first ping arrive before the rounds start
    samples = []
    for i, item in enumerate(items):
        arrived.clear()
        start = time.perf_counter()
        send(item)
        if not arrived.wait(2.0):
            raise RuntimeError("bench: a ping got no pong within 2 s")
        if i >= WARMUP_ROUNDS:
            samples.append((time.perf_counter() - start) * 1e6)
    return samples


def _block(mode: str, endpoint: str, rounds: int) -> list[float]:
    """One block: a fresh echo process of ``mode`` and a fresh pinging session."""
    echo = _Echo(mode, endpoint)
    try:
        return (_measure_typed if mode == "typed" else _measure_raw)(endpoint, rounds)
    finally:
        echo.close()


def run_bus_bench(rounds: int = 2000, blocks: int = 4) -> BusBenchResult:
    """Alternate typed and raw blocks of ``rounds/blocks`` pings each (ABBA order); medians over all."""
    endpoint = f"tcp/127.0.0.1:{_free_port()}"
    per_block = max(1, rounds // blocks)
    typed: list[float] = []
    raw: list[float] = []
    with open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))):
        for block in range(blocks):
            order = ("typed", "raw") if block % 2 == 0 else ("raw", "typed")
            for mode in order:
                (typed if mode == "typed" else raw).extend(_block(mode, endpoint, per_block))
    return BusBenchResult(
        rtt_p50_us=statistics.median(typed),
        rtt_p99_us=_percentile(typed, 0.99),
        raw_rtt_p50_us=statistics.median(raw),
        raw_rtt_p99_us=_percentile(raw, 0.99),
        rounds=len(typed),
    )
