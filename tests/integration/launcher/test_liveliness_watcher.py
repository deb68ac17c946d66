"""The launcher's liveliness watcher leaves no thread of its own behind once closed.

Zenoh runs a subscriber's Python callback on a thread it starts from the declaring thread, a daemon here,
which the interpreter's exit does not wait for. Left running while the interpreter finalised, that thread
aborted the process ("FATAL: exception not rethrown", exit 134) after ``zendock demo`` had printed why its
stack could not start: once in CI, and 5 times in 260 such demos run four at a time here (0 in 120 since).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import zenoh

from deploy.launcher.health import NODE_TOKENS, LivelinessWatcher


class SlowLoop:
    """Stands in for the event loop: holds Zenoh's callback thread for ``hold_s`` on the first token."""

    def __init__(self, hold_s: float) -> None:
        self.hold_s = hold_s
        self.entered = threading.Event()

    def call_soon_threadsafe(self, callback: Callable[..., Any], *args: Any) -> None:
        if not self.entered.is_set():
            self.entered.set()
            threading.Event().wait(self.hold_s)


def test_closing_the_watcher_waits_for_the_thread_running_its_callback(
    router_endpoint: str, bus: zenoh.Session
) -> None:
    before = set(threading.enumerate())
    loop = SlowLoop(hold_s=0.5)
    watcher = LivelinessWatcher([router_endpoint], loop, lambda: None)  # type: ignore[arg-type]
    watcher.start()
    try:
        assert watcher.connected.wait(10.0), f"the watcher did not connect to {router_endpoint}"
        token = bus.liveliness().declare_token(NODE_TOKENS.replace("**", "watched"))
        assert loop.entered.wait(10.0), "the watcher never saw the token"
    finally:
        watcher.close()
    token.undeclare()
    left = [f"{t.name} (daemon={t.daemon})" for t in threading.enumerate() if t not in before]
    assert not left, f"threads still running after close: {left}"
