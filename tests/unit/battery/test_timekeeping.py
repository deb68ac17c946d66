"""Clock steps that survive resets and leaps; inputs that go stale."""

from __future__ import annotations

import pytest

from services.battery.timekeeping import FreshValue, Step, StepClock


def test_step_clock_gives_the_deltas_of_a_steady_clock() -> None:
    clock = StepClock(max_step_s=2.0)
    assert clock.advance(10.0) == Step(0.0)  # the first reading only sets the reference
    assert clock.advance(10.1).dt_s == pytest.approx(0.1)
    assert clock.advance(11.6).dt_s == pytest.approx(1.5)


def test_step_clock_skips_a_jump_back_and_resumes_from_it() -> None:
    clock = StepClock(max_step_s=2.0)
    clock.advance(100.0)
    assert clock.advance(0.5) == Step(0.0, jumped_back=True)
    assert clock.advance(0.6).dt_s == pytest.approx(0.1)


def test_step_clock_skips_a_leap_forward() -> None:
    clock = StepClock(max_step_s=2.0)
    clock.advance(1.0)
    assert clock.advance(60.0) == Step(0.0, jumped_forward=True)
    assert clock.advance(60.5).dt_s == pytest.approx(0.5)


def test_step_clock_refuses_a_non_positive_limit() -> None:
    with pytest.raises(ValueError, match="max_step_s"):
        StepClock(0.0)


def test_fresh_value_goes_stale_after_its_timeout() -> None:
    contact: FreshValue[bool] = FreshValue(timeout_s=1.0)
    assert contact.get(0.0, False) is False and not contact.ever_received
    contact.update(True, 5.0)
    assert contact.is_fresh(5.9) and contact.get(5.9, False) is True
    assert not contact.is_fresh(6.1) and contact.get(6.1, False) is False


def test_fresh_value_from_the_future_is_stale_and_forget_clears_it() -> None:
    contact: FreshValue[bool] = FreshValue(timeout_s=1.0)
    contact.update(True, 50.0)
    assert contact.get(2.0, False) is False  # the clock was reset after it arrived
    contact.forget()
    assert not contact.ever_received
