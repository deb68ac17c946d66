"""``zendock dock`` speaks at least once a period while it waits, whether or not feedback comes."""

from __future__ import annotations

import io
import threading

from deploy.commands.dock import _FeedbackLines, _wait_repeating
from tests.support.processes import wait_until


def test_the_latest_line_repeats_without_new_feedback_and_a_change_prints_at_once() -> None:
    out = io.StringIO()
    distances = iter(range(100, 0, -1))  # what the robot's pose says at each line: it keeps closing in
    lines = _FeedbackLines(lambda state: (state, f"{state} {next(distances)} cm"), out, repeat_every_s=0.1)
    lines.feedback("NAV_TO_STAGING_POSE")
    lines.feedback("NAV_TO_STAGING_POSE")  # the same state again: no line of its own
    assert out.getvalue() == "NAV_TO_STAGING_POSE 100 cm\n"
    done = threading.Event()
    waiter = threading.Thread(target=lambda: _wait_repeating(done, 30.0, lines))
    waiter.start()
    try:
        wait_until(
            lambda: out.getvalue().count("\n") >= 4,
            timeout_s=20.0,
            describe=lambda: f"no repeated line in 20 s: {out.getvalue()!r}",
        )
        lines.feedback("CONTROLLING")
        wait_until(lambda: "CONTROLLING" in out.getvalue(), timeout_s=5.0, describe=out.getvalue)
    finally:
        done.set()
        waiter.join(5.0)
    printed = out.getvalue().splitlines()
    repeated = [line.split() for line in printed[:4]]
    assert all(state == "NAV_TO_STAGING_POSE" for state, _, _ in repeated), printed
    distances = [int(d) for _, d, _ in repeated]
    assert distances == sorted(distances, reverse=True) and len(set(distances)) == 4, (
        printed
    )  # each one current
    assert any(line.startswith("CONTROLLING") for line in printed)


def test_waiting_ends_with_the_result_or_the_timeout() -> None:
    lines = _FeedbackLines(None, io.StringIO(), repeat_every_s=0.05)
    done = threading.Event()
    assert _wait_repeating(done, 0.2, lines) is False  # no result: the timeout ends it
    done.set()
    assert _wait_repeating(done, 30.0, lines) is True
