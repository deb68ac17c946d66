"""The far end of the bus benchmark: sends every ping straight back as a pong.

``typed``: a zendock node (validated decode, the callback under the executor's rules, validated
re-encode and a publish with sequence number). ``raw``: plain zenoh-python callbacks that pass the
bytes on. Run as ``python -m deploy.bench.echo MODE ENDPOINT``.
"""

from __future__ import annotations

import signal
import sys
import threading

from shared.messages import Twist
from shared.node import RELIABLE, Node
from shared.session import SessionSpec, open_session
from shared.waiting import wait_interruptibly


def ping_key(mode: str) -> str:
    """Each mode has its own keys, so a typed and a raw echo can run side by side."""
    return f"zendock_bench/{mode}/ping"


def pong_key(mode: str) -> str:
    return f"zendock_bench/{mode}/pong"


def run_typed(endpoint: str, stop: threading.Event) -> None:
    with open_session(SessionSpec(connect=(endpoint,))) as session:
        node = Node("bench_echo", session)
        pong = node.create_publisher(Twist, pong_key("typed"), RELIABLE)
        node.create_subscription(Twist, ping_key("typed"), pong.publish, RELIABLE)
        node.declare_ready()
        threading.Thread(target=_shutdown_on, args=(stop, node), daemon=True).start()
        print("ready", flush=True)
        node.spin()
        node.close()


def _shutdown_on(stop: threading.Event, node: Node) -> None:
    stop.wait()
    node.shutdown()


def run_raw(endpoint: str, stop: threading.Event) -> None:
    with open_session(SessionSpec(connect=(endpoint,))) as session:
        pong = session.declare_publisher(pong_key("raw"))
        sub = session.declare_subscriber(ping_key("raw"), lambda sample: pong.put(sample.payload))
        print("ready", flush=True)
        wait_interruptibly(stop)
        sub.undeclare()


def main(mode: str, endpoint: str) -> int:
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    (run_typed if mode == "typed" else run_raw)(endpoint, stop)
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("typed", "raw"):
        print("usage: python -m deploy.bench.echo typed|raw ENDPOINT", file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1], sys.argv[2]))
