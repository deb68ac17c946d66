"""The executor's rule without a bus: callbacks never overlap, and a failing one never escapes."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from shared.executor import Executor, Timer, Work, in_callback


def _executor() -> tuple[Executor, list[BaseException]]:
    errors: list[BaseException] = []
    return Executor(on_error=errors.append), errors


def test_try_run_now_runs_at_once_when_idle_and_marks_the_callback() -> None:
    executor, errors = _executor()
    seen: list[bool] = []
    assert executor.try_run_now(lambda: seen.append(in_callback()))
    assert seen == [True]
    assert not in_callback()
    assert not errors


def test_try_run_now_declines_while_work_is_queued_a_callback_runs_or_stopped() -> None:
    executor, _ = _executor()
    ran: list[str] = []
    with executor.exclusive():  # a callback (or a service's own loop) holds the executor
        assert not executor.try_run_now(ran.append, "busy")
    executor.post(ran.append, "queued")
    assert not executor.try_run_now(ran.append, "behind the queue")
    assert executor.spin(until=lambda: ran == ["queued"], timeout_s=1.0)
    executor.stop()
    assert not executor.try_run_now(ran.append, "stopped")
    assert ran == ["queued"]


def test_a_failing_callback_is_reported_not_raised() -> None:
    executor, errors = _executor()
    boom = RuntimeError("boom")

    def fail() -> None:
        raise boom

    assert executor.try_run_now(fail)
    executor.run_inline(fail)
    assert errors == [boom, boom]
    assert executor.try_run_now(lambda: None)  # the lock was released


def test_a_drain_runs_each_item_as_its_own_callback_until_none() -> None:
    executor, errors = _executor()
    delivered: list[int] = []

    def deliver(n: int) -> None:
        if n == 2:
            raise ValueError("bad message")
        delivered.append(n)

    items: list[Work] = [(deliver, (n,)) for n in (1, 2, 3)]

    def take() -> Work | None:
        return items.pop(0) if items else None

    executor.post_drain(take)
    assert executor.spin(until=lambda: not items and delivered == [1, 3], timeout_s=1.0)
    assert [type(e) for e in errors] == [ValueError]


def test_callbacks_never_overlap_across_threads() -> None:
    executor, errors = _executor()
    inside = threading.Lock()
    overlaps: list[int] = []
    count = [0]

    def callback() -> None:
        if not inside.acquire(blocking=False):
            overlaps.append(1)
            return
        count[0] += 1
        inside.release()

    def offer(n: int) -> None:
        for _ in range(n):
            if not executor.try_run_now(callback):
                executor.post(callback)

    threads = [threading.Thread(target=offer, args=(500,)) for _ in range(3)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert executor.spin(until=lambda: count[0] == 1500, timeout_s=5.0)
    assert not overlaps and not errors


class _SimClock:
    def __init__(self) -> None:
        self.clock_started = False
        self.time_s = 0.0

    def now(self) -> float:
        return self.time_s


def test_a_sim_time_timer_waits_for_the_clock_and_fires_on_its_period() -> None:
    executor, _ = _executor()
    clock = _SimClock()
    fired: list[float] = []
    timer = Timer(executor, 0.05, lambda: fired.append(clock.now()), sim_clock=clock)
    executor.add_timer(timer)
    assert not timer.due()  # no clock yet
    clock.clock_started = True
    assert not timer.due()  # first tick schedules the next
    assert timer.next_due is not None
    clock.time_s = 0.05
    assert timer.due()
    timer.fire()
    assert fired == [0.05]
    timer.cancel()
    assert timer.cancelled and not timer.due()


def test_wall_timer_fires_from_spin() -> None:
    executor, _ = _executor()
    fired: list[int] = []
    tick: Callable[[], Any] = lambda: fired.append(1)  # noqa: E731
    executor.add_timer(Timer(executor, 0.01, tick, sim_clock=None))
    watchdog = threading.Timer(2.0, executor.stop)  # spin's own timeout returns while a wall timer is due
    watchdog.start()
    try:
        assert executor.spin(until=lambda: len(fired) >= 2)
    finally:
        watchdog.cancel()
