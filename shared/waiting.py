"""Waiting on an event in a main thread that must still run its signal handlers.

A module of its own, importing nothing heavy, so lean processes (the router) can wait without loading the
services' runtime (the contracts and what they import; what that weighs: measurement 61).
"""

from __future__ import annotations

import threading
import time

#: How often a main thread waiting on an event comes back to the interpreter to run signal handlers.
SIGNAL_CHECK_S = 0.2


def wait_interruptibly(event: threading.Event, timeout_s: float | None = None) -> bool:
    """``event.wait(timeout_s)`` for a main thread that must still run its signal handlers.

    The kernel may hand SIGINT to any thread, often one of Zenoh's: Python then only marks the handler
    pending, and a main thread asleep in a long ``Event.wait`` does not wake to run it (the router hung
    so after its stop). Waking every ``SIGNAL_CHECK_S`` lets the handler run (or Ctrl-C raise).
    """
    deadline = None if timeout_s is None else time.monotonic() + timeout_s
    while True:
        step = SIGNAL_CHECK_S if deadline is None else min(SIGNAL_CHECK_S, deadline - time.monotonic())
        if step <= 0:
            return event.is_set()
        if event.wait(step):
            return True


__all__ = ["SIGNAL_CHECK_S", "wait_interruptibly"]
