"""The world waits for a moving robot's late driver, within a wall-clock budget per command."""

from __future__ import annotations

import pytest

from services.simulator.pacing import Driver, DriverPacer, PacingParams, rate_report

PARAMS = PacingParams(driver_gap_s=0.15, driver_wait_max_s=0.1)


def test_no_wait_while_commands_are_on_time_or_the_robot_is_still() -> None:
    pacer = DriverPacer(PARAMS)
    assert not pacer.hold(1.0, 0.0, [Driver("r0", 0.9, moving=True)])  # 0.1 s old: on time
    assert not pacer.hold(5.0, 0.0, [Driver("r0", 0.9, moving=False)])  # stopped: nothing to wait for
    assert pacer.holds == 0


def test_waits_for_a_late_command_until_the_budget_is_spent_then_steps_on() -> None:
    pacer = DriverPacer(PARAMS)
    late = [Driver("r0", 1.0, moving=True), Driver("r1", 1.19, moving=True)]
    assert pacer.hold(1.2, 10.00, late)
    assert pacer.hold(1.2, 10.05, late)
    assert not pacer.hold(1.2, 10.11, late)  # 0.11 s of wall time for the same command: step on
    assert not pacer.hold(1.3, 10.12, late)  # still the same command: no new wait
    assert pacer.holds == 1
    fresh = [Driver("r0", 1.3, moving=True), Driver("r1", 1.3, moving=True)]
    assert not pacer.hold(1.31, 10.13, fresh)
    again = [Driver("r0", 1.3, moving=True), Driver("r1", 1.3, moving=True)]
    assert pacer.hold(1.5, 10.20, again)  # a new late command: a new budget
    assert pacer.holds == 2


def test_a_late_pose_holds_the_world_on_its_own_gap_even_with_the_robot_still() -> None:
    """A controller with a stale pose holds its robot still; the world must wait for the pose, not run on."""
    pacer = DriverPacer(PacingParams(driver_gap_s=0.15, driver_wait_max_s=0.1, pose_gap_s=0.3))
    still = Driver("r0", 0.0, moving=False)
    assert not pacer.hold(2.0, 0.0, [still, Driver("r0:pose", 1.8, True, gap_s=0.3)])  # 0.2 s old: on time
    assert pacer.hold(2.0, 0.0, [still, Driver("r0:pose", 1.6, True, gap_s=0.3)])  # 0.4 s old: wait
    assert not pacer.hold(2.0, 0.2, [still, Driver("r0:pose", 1.6, True, gap_s=0.3)])  # budget spent: a dead
    assert pacer.holds == 1  # pose service costs one wait, not a frozen world


def test_held_time_is_counted_by_what_was_late() -> None:
    pacer = DriverPacer(PacingParams(driver_gap_s=0.15, driver_wait_max_s=0.1, pose_gap_s=0.3))
    late_command = [Driver("r0", 0.0, True), Driver("r0:pose", 0.9, True, 0.3)]
    assert pacer.hold(1.0, 10.0, late_command)
    assert not pacer.hold(1.0, 10.02, [Driver("r0", 0.99, True), Driver("r0:pose", 0.9, True, 0.3)])
    pacer.note_held(0.02)
    assert pacer.hold(2.0, 11.0, [Driver("r0", 1.99, True), Driver("r0:pose", 1.0, True, 0.3)])
    assert not pacer.hold(2.0, 11.05, [Driver("r0", 1.99, True), Driver("r0:pose", 1.95, True, 0.3)])
    pacer.note_held(0.05)
    assert pacer.held_by_kind == {"cmd_vel": pytest.approx(0.02), "pose": pytest.approx(0.05)}
    assert pacer.held_s == pytest.approx(0.07) and pacer.holds == 2


def test_the_rate_report_says_how_long_the_world_waited_for_each_kind_of_input() -> None:
    pacer = DriverPacer(PARAMS)
    assert rate_report(60.0, 20.0, 3.0, None) == "real-time factor 3.0 over the last 20 s (target 3.0)"
    assert rate_report(60.0, 20.0, 3.0, pacer).endswith("waited for late drivers 0 times, 0.0 s in all")
    pacer.holds, pacer.held_s, pacer.held_by_kind = 3, 0.6, {"pose": 0.1, "cmd_vel": 0.5}
    assert rate_report(57.0, 20.0, 3.0, pacer) == (
        "real-time factor 2.9 over the last 20 s (target 3.0); waited for late drivers 3 times, 0.6 s in all "
        "(cmd_vel 0.5 s, pose 0.1 s)")
