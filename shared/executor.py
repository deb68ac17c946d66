"""The executor: where a node's callbacks run, and the one rule they keep: they never overlap.

The rule: at most one callback of a node runs at a time, whatever thread runs it, so service code needs
no locks. The executor's run lock is that rule; everything that runs a callback goes through one of the
doors below, and each door either holds the lock or is documented as not needing it:

- :meth:`Executor.try_run_now`: run a callback at once on the calling thread (a Zenoh thread) when the
  executor is idle: nothing queued, not stopped, the lock free. Otherwise it refuses and the caller queues.
  This is the subscription fast path: it saves two thread hand-offs per message.
- :meth:`Executor.post` and :meth:`Executor.post_drain`: queue work; :meth:`Executor.spin` runs it in order,
  then due timers, holding the lock for the whole batch.
- :meth:`Executor.run_inline`: run without the lock, only for tiny, thread-safe work (the clock).
- :meth:`Executor.exclusive`: the lock itself, for a service's own loop thread that shares state with
  its callbacks.

Every callback runs as :meth:`Executor._run` runs it (``try_run_now`` keeps an inlined copy, being every
message's path): the thread is marked as inside a callback (so a blocking request from a callback is
refused, see :func:`in_callback`) and an exception goes to the executor's error reporter, so none reaches
Zenoh's threads or stops the spin loop.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any, Protocol

#: A unit of work: a callable and its arguments.
Work = tuple[Callable[..., Any], tuple[Any, ...]]

_callback_context = threading.local()


def in_callback() -> bool:
    """Whether the calling thread is running one of a node's callbacks now."""
    return bool(getattr(_callback_context, "active", False))


class Executor:
    """Runs queued work and due timers on one thread, in order; callbacks never overlap (module doc)."""

    def __init__(self, on_error: Callable[[BaseException], None]) -> None:
        self._on_error = on_error
        self._cv = threading.Condition()
        self._ready: deque[Work] = deque()
        self._stop = False
        self._timers: list[Timer] = []
        #: Held while any callback runs: callbacks are mutually exclusive whatever thread runs them.
        self._run_lock = threading.Lock()
        #: The earliest sim time a sim-time timer is due; the clock wakes the executor only from then on.
        self.next_sim_due = 0.0

    # --- the doors --------------------------------------------------------------------------------

    def try_run_now(self, fn: Callable[..., Any], *args: Any) -> bool:
        """Run ``fn(*args)`` now on this thread if nothing is queued, the executor runs, and no callback runs;
        ``False`` (nothing run) otherwise, and the caller queues the work instead."""
        if self._ready or self._stop or not self._run_lock.acquire(False):
            return False
        try:
            self._run(fn, args)
        finally:
            self._run_lock.release()
        return True

    def post(self, fn: Callable[..., Any], *args: Any) -> None:
        """Queue ``fn(*args)`` for :meth:`spin` (from any thread)."""
        with self._cv:
            self._ready.append((fn, args))
            self._cv.notify()

    def post_drain(self, take: Callable[[], Work | None]) -> None:
        """Queue a drain of a source: :meth:`spin` runs each work item ``take()`` hands out, each as a callback
        of its own (one failing does not stop the rest), until ``take()`` returns ``None``."""
        self.post(self._drain, take)

    def run_inline(self, fn: Callable[..., Any], *args: Any) -> None:
        """Run ``fn(*args)`` now as a callback but without the lock: only for tiny, thread-safe work."""
        self._run(fn, args)

    def exclusive(self) -> threading.Lock:
        """The run lock: code holding it never runs at the same time as a callback."""
        return self._run_lock

    # --- timers and the spin loop -----------------------------------------------------------------

    def wake(self) -> None:
        with self._cv:
            self._cv.notify()

    def add_timer(self, timer: Timer) -> None:
        with self._cv:
            self._timers.append(timer)
            self.next_sim_due = 0.0  # let the clock wake us to schedule the new timer
            self._cv.notify()

    def remove_timer(self, timer: Timer) -> None:
        with self._cv:
            if timer in self._timers:
                self._timers.remove(timer)

    def stop(self) -> None:
        with self._cv:
            self._stop = True
            self._cv.notify_all()

    def spin(self, until: Callable[[], bool] | None = None, timeout_s: float | None = None) -> bool:
        """Run until stopped, until ``until()`` is true, or until the wall timeout; returns ``until()``'s value."""
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while True:
            if until is not None and until():
                return True
            with self._cv:
                if self._stop:
                    return False
                wait = self._next_wall_wait()
                if deadline is not None:
                    wait = min(wait, deadline - time.monotonic())
                    if wait <= 0 and not self._ready:
                        return bool(until and until())
                if not self._ready and wait > 0:
                    self._cv.wait(min(wait, 0.1))
                work = list(self._ready)
                self._ready.clear()
                timers = list(self._timers)
            with self._run_lock:
                for fn, args in work:
                    self._run(fn, args)
                for timer in timers:
                    if timer.due():
                        self._run(timer.fire, ())
                sim_deadlines = [t.next_due for t in timers if t.uses_sim_time and not t.cancelled]
                self.next_sim_due = min(
                    (d if d is not None else 0.0 for d in sim_deadlines), default=float("inf")
                )

    # --- internals --------------------------------------------------------------------------------

    def _run(self, fn: Callable[..., Any], args: tuple[Any, ...]) -> None:
        """Run one callback: mark the thread as inside a callback, report an exception instead of raising."""
        context = _callback_context
        outer = getattr(context, "active", False)
        context.active = True
        try:
            fn(*args)
        except Exception as exc:
            self._on_error(exc)
        finally:
            context.active = outer

    def _drain(self, take: Callable[[], Work | None]) -> None:
        while (item := take()) is not None:
            self._run(*item)

    def _next_wall_wait(self) -> float:
        wait = 0.1
        for timer in self._timers:
            if not timer.uses_sim_time:
                wait = min(wait, timer.wall_wait())
        return max(wait, 0.0)


class SimClock(Protocol):
    """The simulated clock a sim-time timer reads (a :class:`~shared.node.Node` is one)."""

    @property
    def clock_started(self) -> bool: ...

    def now(self) -> float: ...


#: A timer is due this close before its deadline: sim time is a count of steps times the step (1.05 may be
#: 1.0499999999999998) while deadlines add up periods, so a tick that lands exactly on a deadline must count
#: as on time, or a 20 Hz timer on a 20 Hz clock would fire on every other tick.
TIMER_TOLERANCE_S = 1e-6


class Timer:
    """Calls ``callback`` every ``period_s`` on sim time (``sim_clock``) or, without one, on the wall clock."""

    def __init__(
        self, executor: Executor, period_s: float, callback: Callable[[], Any], sim_clock: SimClock | None
    ) -> None:
        if not period_s > 0:
            raise ValueError(f"timer period must be positive, got {period_s}")
        self._executor = executor
        self._sim_clock = sim_clock
        self.period_s = period_s
        self._callback = callback
        self.uses_sim_time = sim_clock is not None
        self._next: float | None = None
        self.cancelled = False

    def _now(self) -> float:
        return self._sim_clock.now() if self._sim_clock is not None else time.monotonic()

    def due(self) -> bool:
        if self.cancelled:
            return False
        now = self._now()
        if self._sim_clock is not None and not self._sim_clock.clock_started:
            return False
        if self._next is None or now < self._next - 2 * self.period_s - 1.0:
            self._next = now + self.period_s  # first tick, or the clock jumped back (simulator reset)
            return False
        return now >= self._next - TIMER_TOLERANCE_S

    @property
    def next_due(self) -> float | None:
        """When the timer fires next on its clock (``None`` before its first tick is scheduled)."""
        return self._next

    def wall_wait(self) -> float:
        if self._next is None:
            return 0.0
        return self._next - time.monotonic()

    def fire(self) -> None:
        now = self._now()
        assert self._next is not None
        self._next += self.period_s
        if self._next <= now:  # fell behind: skip the missed ticks rather than bursting
            self._next = now + self.period_s
        self._callback()

    def cancel(self) -> None:
        self.cancelled = True
        self._executor.remove_timer(self)
