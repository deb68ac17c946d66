"""Round-trip latency of zendock's typed publish/subscribe against raw zenoh-python, same run.

Both echoes are separate processes on one loopback router. The typed path decodes and validates on
arrival, runs the callback under the node's executor rules and validates again on publishing (with the
encoding and the sequence-and-publisher attachment every zendock sample carries); the raw path passes
bytes through zenoh-python callbacks. The report gives medians and p99 of each and their ratio.

What makes the comparison fair: both sides use declared publishers with the same QoS and
subscriber callbacks; the payloads are the same 84-byte Twist; the messages (typed) and payloads
(raw) are built before the clock starts, as the raw payload always was (making a message is the
application's work, not the bus's). Both echoes run for the whole bench and the pinger alternates
between them round by round, in ABBA order: machine load on a shared host drifts over seconds, and
with blocks of rounds a drift would land on one path more than the other; round by round both paths
see the same machine.
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from deploy.bench.echo import ping_key, pong_key
from deploy.bench.processes import free_port
from deploy.percentiles import median, percentile
from shared.messages import Twist
from shared.node import RELIABLE, Node
from shared.session import SessionSpec, open_session


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


class _Echo:
    def __init__(self, mode: str, endpoint: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "deploy.bench.echo", mode, endpoint],
            stdout=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
        assert self.proc.stdout is not None
        if self.proc.stdout.readline().strip() != "ready":
            self.close()
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


class _Path:
    """One side of the comparison in the pinging process: send an item, wait for its pong."""

    def __init__(self, send: Callable[[Any], object], arrived: threading.Event, items: list[Any]) -> None:
        self.send = send
        self.arrived = arrived
        self.items = items
        self.samples: list[float] = []

    def wait_for_route(self) -> None:
        """The echo is ready when its subscriber is declared, but the router may learn of it (or of ours)
        a little later on a loaded machine: the first ping is repeated until a pong shows the route is up."""
        deadline = time.monotonic() + 10.0
        while True:
            self.arrived.clear()
            self.send(self.items[0])
            if self.arrived.wait(0.25):
                return
            if time.monotonic() > deadline:
                raise RuntimeError("bench: the echo never answered")

    def round_trip(self, index: int) -> float:
        self.arrived.clear()
        start = time.perf_counter()
        self.send(self.items[index])
        if not self.arrived.wait(2.0):
            raise RuntimeError("bench: a ping got no pong within 2 s")
        return (time.perf_counter() - start) * 1e6


def _interleave(typed: _Path, raw: _Path, rounds: int) -> None:
    """Round trips in ABBA order (typed, raw, raw, typed, ...); the warm-up rounds are not kept."""
    for path in (typed, raw):
        path.wait_for_route()
    time.sleep(0.3)  # let any answer to a repeated first ping arrive before the rounds start
    for i in range(rounds + WARMUP_ROUNDS):
        order = (typed, raw) if i % 2 == 0 else (raw, typed)
        for path in order:
            rtt = path.round_trip(i)
            if i >= WARMUP_ROUNDS:
                path.samples.append(rtt)


def _measure(endpoint: str, rounds: int) -> tuple[list[float], list[float]]:
    """Typed and raw round trips from one process: a zendock node on one session, raw zenoh on another."""
    typed_arrived, raw_arrived = threading.Event(), threading.Event()
    spec = SessionSpec(connect=(endpoint,))
    with (
        open_session(spec) as typed_session,
        open_session(spec) as raw_session,
        Node("bench_ping", typed_session) as node,
    ):
        ping = node.create_publisher(Twist, ping_key("typed"), RELIABLE)
        node.create_subscription(Twist, pong_key("typed"), lambda _m: typed_arrived.set(), RELIABLE)
        spinner = threading.Thread(target=node.spin, daemon=True)
        spinner.start()
        raw_pub = raw_session.declare_publisher(ping_key("raw"))
        raw_sub = raw_session.declare_subscriber(pong_key("raw"), lambda _s: raw_arrived.set())
        typed = _Path(ping.publish, typed_arrived, _twists(rounds))
        raw = _Path(raw_pub.put, raw_arrived, [msg.encode() for msg in _twists(rounds)])
        try:
            _interleave(typed, raw, rounds)
        finally:
            node.shutdown()
            spinner.join(2)
            raw_sub.undeclare()
            raw_pub.undeclare()
    return typed.samples, raw.samples


def run_bus_bench(rounds: int = 4000) -> BusBenchResult:
    """``rounds`` round trips on each path, interleaved; medians and p99 of each."""
    if rounds < 1:
        raise ValueError(f"rounds must be at least 1, got {rounds}")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))):
        echoes: list[_Echo] = []
        try:
            for mode in ("typed", "raw"):
                echoes.append(_Echo(mode, endpoint))
            typed, raw = _measure(endpoint, rounds)
        finally:
            for echo in echoes:
                echo.close()
    return BusBenchResult(
        rtt_p50_us=median(typed),
        rtt_p99_us=percentile(typed, 0.99),
        raw_rtt_p50_us=median(raw),
        raw_rtt_p99_us=percentile(raw, 0.99),
        rounds=len(typed),
    )
