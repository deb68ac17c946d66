"""Round-trip latency of zendock's typed publish/subscribe against raw zenoh-python, same run.

Both sides are separate processes on one loopback router. The typed path decodes and validates on
arrival, runs the callback on the node's executor and validates again on publishing; the raw path
copies bytes in Zenoh's callback. Rounds alternate between the two in blocks so machine noise hits
both alike; the report gives medians and p99 of each and their ratio.
"""

from __future__ import annotations

import socket
import statistics
import subprocess
import sys
import threading
import time
from dataclasses import dataclass

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


def _measure_typed(node: Node, rounds: int) -> list[float]:
    arrived = threading.Event()
    ping = node.create_publisher(Twist, PING_KEY, RELIABLE)
    sub = node.create_subscription(Twist, PONG_KEY, lambda _m: arrived.set(), RELIABLE)
    spinner = threading.Thread(target=node.spin, daemon=True)
    spinner.start()
    samples = _ping_loop(lambda i: ping.publish(Twist.planar(0.001 * i, 0.5)), arrived, rounds)
    node.shutdown()
    spinner.join(2)
    sub.undeclare()
    ping.undeclare()
    return samples


def _measure_raw(endpoint: str, rounds: int) -> list[float]:
    arrived = threading.Event()
    payload = Twist.planar(0.5, 0.5).encode()
    with open_session(SessionSpec(connect=(endpoint,))) as session:
        pub = session.declare_publisher(PING_KEY)
        sub = session.declare_subscriber(PONG_KEY, lambda _s: arrived.set())
        samples = _ping_loop(lambda _i: pub.put(payload), arrived, rounds)
        sub.undeclare()
    return samples


def _ping_loop(send, arrived: threading.Event, rounds: int) -> list[float]:  # type: ignore[no-untyped-def]
    samples = []
    for i in range(rounds + 50):  # the first 50 warm up routes and caches
        arrived.clear()
        start = time.perf_counter()
        send(i)
        if not arrived.wait(2.0):
            raise RuntimeError("bench: a ping got no pong within 2 s")
        if i >= 50:
            samples.append((time.perf_counter() - start) * 1e6)
    return samples


def run_bus_bench(rounds: int = 2000, blocks: int = 4) -> BusBenchResult:
    """Alternate typed and raw blocks of ``rounds/blocks`` pings each; medians over all."""
    endpoint = f"tcp/127.0.0.1:{_free_port()}"
    per_block = max(1, rounds // blocks)
    typed: list[float] = []
    raw: list[float] = []
    with open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))):
        for _ in range(blocks):
            echo = _Echo("typed", endpoint)
            try:
                with open_session(SessionSpec(connect=(endpoint,))) as session:
                    typed += _measure_typed(Node("bench_ping", session), per_block)
            finally:
                echo.close()
            echo = _Echo("raw", endpoint)
            try:
                raw += _measure_raw(endpoint, per_block)
            finally:
                echo.close()
    return BusBenchResult(
        rtt_p50_us=statistics.median(typed),
        rtt_p99_us=_percentile(typed, 0.99),
        raw_rtt_p50_us=statistics.median(raw),
        raw_rtt_p99_us=_percentile(raw, 0.99),
        rounds=len(typed),
    )
