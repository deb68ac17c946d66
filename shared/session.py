"""Zenoh session configuration with explicit endpoints and no multicast scouting.

zendock never relies on discovery by multicast: every process connects to (or listens on) the endpoints
it is given, so tests on free ports and several stacks on one machine never meet by accident.

A process that opens a session also lets Zenoh's callback threads finish at exit
(:func:`finish_callback_threads`): zenoh-python runs each Python callback on a thread of its own, a daemon
when the thread that declared the callback is one (an executor spun by ``spin_in_background``, a
container's member), and the interpreter does not wait for daemon threads. One that wakes while the
interpreter finalises is made to exit through Rust's ``catch_unwind``, and the process aborts ("FATAL:
exception not rethrown", exit 134): the failure that ended a CI run in a launcher thread (measurement 128).
"""

from __future__ import annotations

import atexit
import json
import threading
import time
from pathlib import Path

import msgspec
import zenoh

DEFAULT_ROUTER_ENDPOINT = "tcp/127.0.0.1:7447"
#: Batches a link may queue at the data priority, where every zendock message goes (Zenoh's default: 2).
#: A simulator step puts several express samples at once (clock, odometry, tf, ranges, the dock's contact),
#: each its own batch, and a camera frame is five; with two slots, whatever finds the queue full for 1 ms
#: is dropped. On a busy machine the sending thread is often that late, and recording everything while the
#: camera streamed lost samples (measurement 59). Sixteen 64 kB batches hold a step and a frame.
TX_QUEUE_BATCHES = 16


class SessionSpec(msgspec.Struct, frozen=True):
    """How a process joins the Zenoh network."""

    mode: str = "client"  # client | peer | router
    connect: tuple[str, ...] = (DEFAULT_ROUTER_ENDPOINT,)
    listen: tuple[str, ...] = ()
    config_file: str | None = None
    #: Extra json5 settings as (path, json-value) pairs, applied last.
    overrides: tuple[tuple[str, str], ...] = ()


def make_config(spec: SessionSpec) -> zenoh.Config:
    """Build a zenoh.Config: the file (if any) first, then mode, endpoints and the no-multicast rule.

    Without a file, zendock's transport settings apply too (a file decides them itself): no shared memory,
    and :data:`TX_QUEUE_BATCHES` send batches at the data priority.
    """
    if spec.mode not in ("client", "peer", "router"):
        raise ValueError(f"zenoh mode must be client, peer or router, got {spec.mode!r}")
    if spec.config_file:
        path = Path(spec.config_file)
        if not path.is_file():
            raise ValueError(f"zenoh config file {path} does not exist")
        conf = zenoh.Config.from_file(str(path))
    else:
        conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps(spec.mode))
    conf.insert_json5("scouting/multicast/enabled", "false")
    # Shared memory off: every receiver maps each sender's 16 MiB pool, which costs tens of MB of RSS per
    # process, and zendock's messages are small. Deeper send queues: see TX_QUEUE_BATCHES.
    if not spec.config_file:
        conf.insert_json5("transport/shared_memory/enabled", "false")
        conf.insert_json5("transport/link/tx/queue/size/data", str(TX_QUEUE_BATCHES))
    if spec.connect:
        conf.insert_json5("connect/endpoints", json.dumps(list(spec.connect)))
    if spec.listen:
        conf.insert_json5("listen/endpoints", json.dumps(list(spec.listen)))
    elif spec.mode != "router":
        conf.insert_json5("listen/endpoints", "[]")
    if spec.mode == "client":
        # Keep trying to reach the router instead of failing at start-up, so start order does not matter.
        conf.insert_json5("connect/timeout_ms", "-1")
        conf.insert_json5("connect/exit_on_failure", "false")
    for path_key, value in spec.overrides:
        conf.insert_json5(path_key, value)
    return conf


#: zenoh-python's name for the thread it runs a Python callback on ends so.
CALLBACK_THREAD_SUFFIX = "(pyo3-closure)"
#: How long, in all, exit waits for Zenoh's daemon callback threads (a session left open keeps its
#: subscribers' threads alive, and exit then waits this long for nothing).
CALLBACK_THREADS_AT_EXIT_S = 1.0
_at_exit = threading.Lock()
_registered = False


def finish_callback_threads(timeout_s: float = CALLBACK_THREADS_AT_EXIT_S) -> None:
    """Wait (``timeout_s`` in all) for Zenoh's daemon callback threads to end.

    Run at exit, after the non-daemon threads are joined and before the interpreter finalises; a closed
    session's threads end within moments of their last callback."""
    deadline = time.monotonic() + timeout_s
    current = threading.current_thread()
    for thread in threading.enumerate():
        if thread.daemon and thread is not current and thread.name.endswith(CALLBACK_THREAD_SUFFIX):
            thread.join(max(0.0, deadline - time.monotonic()))


def open_session(spec: SessionSpec) -> zenoh.Session:
    """Open a session; use it as a context manager so it is always closed. The first one also registers
    :func:`finish_callback_threads` to run at exit."""
    global _registered
    with _at_exit:
        if not _registered:
            atexit.register(finish_callback_threads)
            _registered = True
    return zenoh.open(make_config(spec))
