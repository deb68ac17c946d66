"""Time steps from a clock that may jump, and inputs that go stale.

A simulator's clock restarts from zero on a reset, and a wall clock leaps when a process is
suspended: integrating over either would drain (or fill) the battery at once. :class:`StepClock`
turns clock readings into steps and refuses the implausible ones; :class:`FreshValue` keeps the
latest reading of an input together with when it arrived, so a silent publisher reads as absent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Generic, TypeVar

T = TypeVar("T")


@dataclass(frozen=True, slots=True)
class Step:
    """What :meth:`StepClock.advance` saw: ``dt_s`` to integrate (0 when skipped), and why it skipped."""

    dt_s: float
    jumped_back: bool = False
    jumped_forward: bool = False


class StepClock:
    """Successive clock readings -> integration steps.

    A reading earlier than the last one (a reset) or more than ``max_step_s`` after it (a leap) gives a
    zero step and becomes the new reference, so integration resumes from there.
    """

    def __init__(self, max_step_s: float) -> None:
        if not (math.isfinite(max_step_s) and max_step_s > 0.0):
            raise ValueError(f"max_step_s must be a positive number, got {max_step_s!r}")
        self.max_step_s = max_step_s
        self.last_s: float | None = None

    def advance(self, now_s: float) -> Step:
        last, self.last_s = self.last_s, now_s
        if last is None:
            return Step(0.0)
        dt_s = now_s - last
        if dt_s < 0.0:
            return Step(0.0, jumped_back=True)
        if dt_s > self.max_step_s:
            return Step(0.0, jumped_forward=True)
        return Step(dt_s)


class FreshValue(Generic[T]):
    """The latest value of an input and when it arrived; older than ``timeout_s`` it reads as stale."""

    def __init__(self, timeout_s: float) -> None:
        if not (math.isfinite(timeout_s) and timeout_s > 0.0):
            raise ValueError(f"timeout_s must be a positive number, got {timeout_s!r}")
        self.timeout_s = timeout_s
        self.value: T | None = None
        self.received_s: float | None = None

    def update(self, value: T, now_s: float) -> None:
        self.value = value
        self.received_s = now_s

    def forget(self) -> None:
        self.value = None
        self.received_s = None

    @property
    def ever_received(self) -> bool:
        return self.received_s is not None

    def is_fresh(self, now_s: float) -> bool:
        """Received within ``timeout_s`` before ``now_s`` (a reading from the future, after a clock reset, is not)."""
        if self.received_s is None:
            return False
        age_s = now_s - self.received_s
        return 0.0 <= age_s <= self.timeout_s

    def get(self, now_s: float, default: T) -> T:
        """The value while fresh, else ``default``."""
        if self.value is None or not self.is_fresh(now_s):
            return default
        return self.value
