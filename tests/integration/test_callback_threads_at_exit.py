"""A process whose Zenoh callback is still running on a daemon thread when it exits ends cleanly.

zenoh-python runs a callback on a thread of its own, a daemon when the declaring thread is one (here: a
query sent from a daemon thread, as ``call_async`` from an executor spun by ``spin_in_background``). If
that thread wakes while the interpreter finalises, it is made to exit through Rust's ``catch_unwind`` and
the process aborts with exit 134; the process below arranges exactly that (its own exit hook holds
finalisation back until just before the callback returns), and aborted every time before
``shared.session`` waited for such threads at exit.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

from tests.support.processes import REPO_ROOT

SCRIPT = textwrap.dedent(
    """
    import atexit, sys, threading, time
    import zenoh
    from shared.session import SessionSpec, open_session

    session = open_session(SessionSpec(mode="peer", connect=(), listen=("tcp/127.0.0.1:0",)))
    key = "zendock/test/slow_reply"
    queryable = session.declare_queryable(key, lambda query: query.reply(key, "x"))
    answering = threading.Event()
    CALLBACK_S = 0.3

    def on_reply(reply):
        answering.set()
        time.sleep(CALLBACK_S)  # still in Python when the interpreter finalises

    def ask():
        session.get(key, zenoh.handlers.Callback(on_reply, lambda: None))

    threading.Thread(target=ask, daemon=True).start()
    if not answering.wait(10):
        sys.exit("no reply within 10 s")
    began = time.monotonic()
    # Registered after open_session's, so it runs first: finalisation then begins 10 ms before the
    # callback wakes, unless something waits for it.
    atexit.register(lambda: time.sleep(max(0.0, CALLBACK_S - 0.01 - (time.monotonic() - began))))
    queryable.undeclare()
    session.close()
    """
)


def test_exit_waits_for_a_daemon_callback_thread_instead_of_aborting() -> None:
    outcomes = []
    for _ in range(3):
        done = subprocess.run(
            [sys.executable, "-c", SCRIPT], cwd=REPO_ROOT, capture_output=True, text=True, timeout=60
        )
        outcomes.append(done.returncode)
        assert done.returncode == 0, (
            f"exit codes {outcomes} (-6 or 134: aborted at exit):\n{done.stderr[-2000:]}"
        )
