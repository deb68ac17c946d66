"""Health checks: liveliness tokens seen by one Zenoh client session, and exec tests.

A zendock service declares ``node_token_key(namespace, node)`` once it is ready, so "the token is alive"
is the readiness probe, and a crashed service's token disappears with its session. Zenoh runs callbacks on
its own threads: events are handed to the asyncio loop with ``call_soon_threadsafe``.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import zenoh

from shared.names import GRAPH_PREFIX
from shared.session import SessionSpec, open_session

NODE_TOKENS = f"{GRAPH_PREFIX}/node/**"
_OPEN_ATTEMPT_MS = 1000
#: How long closing waits for Zenoh's callback thread to end (it ends within milliseconds of the close).
_DISPATCH_END_S = 2.0


class LivelinessWatcher:
    """Tracks which node tokens are alive, and since when (monotonic time of the last PUT).

    The session is opened on a background thread, retrying until the router answers, so the supervisor
    can start the router itself. ``on_change`` runs on the event loop after every token event.
    ``config_file`` is a Zenoh json5 file applied first (the credentials of a secured router).
    """

    def __init__(
        self,
        connect: Sequence[str],
        loop: asyncio.AbstractEventLoop,
        on_change: Callable[[], None],
        config_file: str | None = None,
    ) -> None:
        self._spec = SessionSpec(
            mode="client",
            connect=tuple(connect),
            config_file=config_file,
            overrides=(("connect/timeout_ms", str(_OPEN_ATTEMPT_MS)), ("connect/exit_on_failure", "true")),
        )
        self._loop = loop
        self._on_change = on_change
        self._alive_since: dict[str, float] = {}
        self._closing = threading.Event()
        self._lock = threading.Lock()
        self._session: zenoh.Session | None = None
        self._subscriber: zenoh.Subscriber[None] | None = None
        self.connected = threading.Event()
        self._thread = threading.Thread(target=self._connect, name="zendock-liveliness", daemon=True)
        #: Zenoh runs the callbacks on a Python thread of its own, made by the thread that declares the
        #: subscriber: a daemon here, so the interpreter's exit does not wait for it (see :meth:`close`).
        self._dispatcher: threading.Thread | None = None
        self._dispatch_ended = threading.Event()

    def start(self) -> None:
        self._thread.start()

    def alive_since(self, key: str) -> float | None:
        return self._alive_since.get(key)

    def _connect(self) -> None:
        while not self._closing.is_set():
            try:
                session = open_session(self._spec)
            except Exception:  # zenoh.ZError: no router yet
                self._closing.wait(0.2)
                continue
            with self._lock:
                if self._closing.is_set():
                    session.close()
                    return
                self._session = session
                self._subscriber = session.liveliness().declare_subscriber(
                    NODE_TOKENS, zenoh.handlers.Callback(self._on_sample, self._on_dispatch_end), history=True
                )
            self.connected.set()
            return

    def _on_dispatch_end(self) -> None:
        """Zenoh's last call on the thread that ran :meth:`_on_sample`, once the subscriber is gone."""
        self._dispatcher = threading.current_thread()
        self._dispatch_ended.set()

    def _on_sample(self, sample: zenoh.Sample) -> None:
        alive = sample.kind == zenoh.SampleKind.PUT
        with contextlib.suppress(RuntimeError):  # the loop is closed: the supervisor is gone
            self._loop.call_soon_threadsafe(self._apply, str(sample.key_expr), alive, time.monotonic())

    def _apply(self, key: str, alive: bool, when: float) -> None:
        if alive:
            self._alive_since[key] = when
        else:
            self._alive_since.pop(key, None)
        self._on_change()

    def close_within(self, timeout_s: float) -> bool:
        """Blocking: ``close`` on a daemon thread, waiting at most ``timeout_s``; False if it is still closing.

        A Zenoh session's close can stall (a router that stopped answering mid-close); stopping the stack
        must not stall with it, and a daemon thread does not keep the process alive.
        """
        closer = threading.Thread(target=self.close, name="zendock-liveliness-close", daemon=True)
        closer.start()
        closer.join(timeout_s)
        return not closer.is_alive()

    def close(self) -> None:
        """Blocking (run it off the loop): undeclare and close the session.

        The connecting thread is waited for first (one attempt lasts at most ``_OPEN_ATTEMPT_MS``): left
        inside Zenoh's open while the interpreter exits (a stack that failed before its router answered),
        it came back to Python during finalization and the process aborted ("FATAL: exception not
        rethrown", exit 134) after printing why the run had ended.

        Zenoh's callback thread is waited for last, for the same reason: it ends only once Zenoh drops the
        closed subscriber's channel, which can come after ``close`` returns. Left waiting in native code
        while the interpreter exited, it took the same abort when it woke (5 in 260 ``demo`` runs whose
        battery could not start, four at a time; a core dump showed this thread).
        """
        self._closing.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(_OPEN_ATTEMPT_MS / 1000.0 + 1.0)
        with self._lock:
            session, subscriber = self._session, self._subscriber
            self._session = self._subscriber = None
        if subscriber is not None:
            with contextlib.suppress(Exception):
                subscriber.undeclare()
        if session is not None:
            with contextlib.suppress(Exception):
                session.close()
        if subscriber is not None and self._dispatch_ended.wait(_DISPATCH_END_S):
            dispatcher = self._dispatcher
            if dispatcher is not None and dispatcher is not threading.current_thread():
                dispatcher.join(_DISPATCH_END_S)


async def run_check(argv: Sequence[str], *, cwd: Path, env: dict[str, str], timeout_s: float) -> bool:
    """One exec health test: True when it exits 0 within ``timeout_s`` (its whole group is killed otherwise)."""
    try:
        proc = await asyncio.create_subprocess_exec(
            *argv,
            cwd=str(cwd),
            env=env,
            stdin=asyncio.subprocess.DEVNULL,
            stdout=asyncio.subprocess.DEVNULL,
            stderr=asyncio.subprocess.DEVNULL,
            start_new_session=True,
        )
    except OSError:
        return False
    try:
        # asyncio.timeout, not wait_for: on Python 3.11 wait_for swallows a cancellation that arrives just as
        # the test's process exits, and the supervisor's health loop then ran on after its stop
        async with asyncio.timeout(timeout_s):
            return await proc.wait() == 0
    except TimeoutError:
        return False
    finally:
        if proc.returncode is None:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGKILL)
            await proc.wait()
