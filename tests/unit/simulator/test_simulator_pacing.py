"""The world waits for a moving robot's late driver, within a wall-clock budget per command."""

from __future__ import annotations

import pytest

from services.simulator.pacing import (
    CATCH_UP_FACTOR,
    CATCH_UP_LIMIT_S,
    HOLD_LAPSE_S,
    CommandCadence,
    Driver,
    DriverPacer,
    HandoffHold,
    PacingParams,
    StepPacer,
    pacing_stats,
    rate_report,
)

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


def test_a_wait_that_runs_out_is_counted_once_with_what_it_waited_for() -> None:
    pacer = DriverPacer(PARAMS)
    late = [Driver("r0", 1.0, moving=True)]
    assert pacer.hold(1.2, 10.0, late)
    assert not pacer.hold(1.2, 10.11, late) and not pacer.hold(1.21, 10.12, late)
    assert pacer.gave_up == 1 and pacer.gave_up_after_s == 0.1
    assert pacer.gave_up_on == (("r0", pytest.approx(0.2)),)
    assert pacing_stats(pacer, 1.21)["pacing_gave_up"] == 1.0


def test_a_late_pose_holds_the_world_on_its_own_gap_even_with_the_robot_still() -> None:
    """A controller with a stale pose holds its robot still; the world must wait for the pose, not run on."""
    pacer = DriverPacer(PacingParams(driver_gap_s=0.15, driver_wait_max_s=0.1, pose_gap_s=0.3))
    still = Driver("r0", 0.0, moving=False)
    assert not pacer.hold(2.0, 0.0, [still, Driver("r0:pose", 1.8, True, gap_s=0.3)])  # 0.2 s old: on time
    assert pacer.hold(2.0, 0.0, [still, Driver("r0:pose", 1.6, True, gap_s=0.3)])  # 0.4 s old: wait
    assert not pacer.hold(2.0, 0.2, [still, Driver("r0:pose", 1.6, True, gap_s=0.3)])  # budget spent: a dead
    assert pacer.holds == 1  # pose service costs one wait, not a frozen world


def test_lockstep_holds_a_moving_robot_to_its_own_controllers_period() -> None:
    """A 20 Hz controller's command is late 0.06 s after the last (1.2 periods), not after driver_gap_s; a
    10 Hz one's after 0.12 s; the cadence counts one step's commands once and starts again after a pause."""
    step = 0.01
    fast, slow = CommandCadence(), CommandCadence()
    assert fast.gap_s(PARAMS, step) is None  # not known yet: the pacer's default gap
    for i in range(6):
        fast.heard(1.0 + 0.05 * i, step)
        fast.heard(1.0 + 0.05 * i + 0.001, step)  # a second command in the same step
        slow.heard(1.0 + 0.1 * i, step)
    assert fast.period_s() == pytest.approx(0.05) and fast.gap_s(PARAMS, step) == pytest.approx(0.06)
    assert slow.gap_s(PARAMS, step) == pytest.approx(0.12)
    pacer = DriverPacer(PARAMS)
    last = 1.25
    assert not pacer.hold(1.30, 0.0, [Driver("r0", last, True, fast.gap_s(PARAMS, step))])
    assert pacer.hold(1.32, 0.0, [Driver("r0", last, True, fast.gap_s(PARAMS, step))])  # 0.07 s: late
    assert fast.gap_s(PacingParams(lockstep_factor=0.0), step) is None  # lockstep off: the default gap
    fast.heard(3.0, step)  # after a pause: a new stream, its period unknown again
    assert fast.period_s() is None


def test_a_handoff_holds_the_world_from_its_tick_until_a_command_that_moves_answers_it() -> None:
    handoff = HandoffHold()
    handoff.heard(10.0, "docking", hold=True, now_s=10.02)
    assert handoff.tick_s == 10.0
    pacer = DriverPacer(PARAMS)
    assert not pacer.hold(10.1, 0.0, [Driver("r0:hold", handoff.tick_s, True)])  # within the gap
    assert pacer.hold(10.2, 0.0, [Driver("r0:hold", handoff.tick_s, True)])  # past it: wait
    handoff.driven(10.05, moving=False)  # a stop (the planner still planning) does not end it
    assert handoff.tick_s == 10.0
    handoff.driven(9.9, moving=True)  # a moving command from before the handoff does not either
    assert handoff.tick_s == 10.0
    handoff.driven(10.15, moving=True)  # the next driver drives
    assert handoff.tick_s is None


def test_a_handoff_is_let_go_by_its_holder_and_a_stale_one_is_ignored() -> None:
    handoff = HandoffHold()
    handoff.heard(5.0, "docking", hold=True, now_s=5.0)
    handoff.heard(5.1, "someone else", hold=False, now_s=5.1)  # not theirs to let go
    assert handoff.tick_s == 5.0
    handoff.heard(5.2, "docking", hold=False, now_s=5.2)
    assert handoff.tick_s is None
    handoff.driven(6.0, moving=True)
    handoff.heard(5.9, "docking", hold=True, now_s=6.1)  # arrived after the robot was driven on a later tick
    assert handoff.tick_s is None
    handoff.heard(99.0, "docking", hold=True, now_s=7.0)  # a tick from the future counts as now
    assert handoff.tick_s == 7.0


def test_a_hold_for_a_holder_that_drives_next_is_ended_only_by_its_let_go() -> None:
    """The docking service cancels the planner's goal to drive itself: the planner's last moving commands,
    still on their way and answering later ticks, must not end the hold."""
    handoff = HandoffHold()
    handoff.driven(8.0, moving=True)
    handoff.heard(
        8.0, "docking", hold=True, now_s=8.0, until_driven=False
    )  # not stale: it does not wait for one
    assert handoff.tick_s == 8.0
    handoff.driven(8.05, moving=True)
    assert handoff.tick_s == 8.0
    handoff.heard(8.1, "docking", hold=False, now_s=8.1)
    assert handoff.tick_s is None


def test_a_hold_lapses_once_the_world_has_run_well_past_it() -> None:
    """A wait that ran out of budget, or a holder that died: the hold is waited for once, not again each
    time another input comes late beside it."""
    handoff = HandoffHold()
    handoff.heard(3.0, "docking", hold=True, now_s=3.0, until_driven=False)
    assert handoff.current(3.0 + HOLD_LAPSE_S) == 3.0
    assert handoff.current(3.01 + HOLD_LAPSE_S) is None
    assert handoff.tick_s is None
    handoff.heard(4.0, "docking", hold=True, now_s=4.6, until_driven=False)  # arrived 0.6 s late
    assert handoff.current(4.6) == 4.0  # counted from its arrival
    assert handoff.current(4.61 + HOLD_LAPSE_S) is None


def test_an_announced_hold_alone_is_waited_for_on_its_own_longer_budget() -> None:
    """A controller that said it is at work (a plan, a costmap change) is waited for up to hold_wait_max_s;
    a late command beside the hold brings back the shorter budget of a command."""
    params = PacingParams(driver_gap_s=0.15, driver_wait_max_s=0.1, hold_wait_max_s=2.0)
    pacer = DriverPacer(params)
    hold = [Driver("r0:hold", 1.0, True)]
    assert pacer.hold(2.0, 10.0, hold)
    assert pacer.hold(2.0, 11.9, hold)  # 1.9 s of wall time: still waiting
    assert not pacer.hold(2.0, 12.0, hold)  # the budget is spent: step on
    assert pacer.gave_up == 1 and pacer.gave_up_after_s == 2.0  # what the log says it waited
    with_command = [Driver("r0:hold", 3.0, True), Driver("r1", 3.0, moving=True)]
    assert pacer.hold(4.0, 20.0, with_command)
    assert not pacer.hold(4.0, 20.11, with_command)


def test_time_held_for_a_handoff_is_counted_apart() -> None:
    pacer = DriverPacer(PARAMS)
    assert pacer.hold(2.0, 0.0, [Driver("r0:hold", 1.0, True)])
    assert not pacer.hold(2.0, 0.05, [])
    pacer.note_held(0.05)
    assert pacer.held_by_kind == {"hold": 0.05}


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
        "(cmd_vel 0.5 s, pose 0.1 s)"
    )


def _run(
    pacer: StepPacer,
    until_wall_s: float,
    late_between: tuple[float, float] | None = None,
    stall: tuple[float, float] | None = None,
    dt_s: float = 0.01,
    oversleep_s: float = 0.0,
    step_cost_s: float = 0.0,
) -> list[float]:
    """Drive ``pacer`` on a virtual wall clock; returns the wall time of every step. ``late_between``: a moving
    robot's command is late in that wall window; ``stall``: the machine stops at ``stall[0]`` for ``stall[1]``;
    every sleep wakes ``oversleep_s`` late and every step takes ``step_cost_s``."""
    wall = sim = 0.0
    steps: list[float] = []
    stalled = False
    while wall < until_wall_s:
        if stall is not None and not stalled and wall >= stall[0]:
            wall += stall[1]
            stalled = True
        late = late_between is not None and late_between[0] <= wall < late_between[1]
        drivers = [Driver("r1", sim - 1.0 if late else sim, moving=True)]
        tick = pacer.tick(wall, sim, lambda drivers=drivers: drivers)
        if tick.step:
            steps.append(wall)
            sim += dt_s
            wall += step_cost_s
        else:
            wall += max(tick.sleep_s, 1e-5) + oversleep_s
    return steps


def test_the_world_keeps_its_target_rate_and_sleeps_between_steps() -> None:
    steps = _run(StepPacer(0.01, 2.0, DriverPacer(PARAMS), 0.0), 1.0)
    assert len(steps) == pytest.approx(200, abs=1), "2x real time: 200 steps of 10 ms in one wall second"
    gaps = [b - a for a, b in zip(steps, steps[1:], strict=False)]
    assert min(gaps) >= 0.005 - 1e-9


def test_time_held_for_a_late_driver_is_made_up_no_faster_than_the_catch_up_factor() -> None:
    pacer = StepPacer(0.01, 2.0, DriverPacer(PARAMS), 0.0)
    steps = _run(pacer, 2.0, late_between=(0.5, 0.55))
    assert pacer.drivers is not None and pacer.drivers.held_s == pytest.approx(0.05, abs=0.002)
    assert len(steps) == pytest.approx(400, abs=1), "the 50 ms held are made up within two wall seconds"
    after = [b - a for a, b in zip(steps, steps[1:], strict=False) if b > 0.56]
    assert min(after) >= 0.005 / CATCH_UP_FACTOR - 1e-9, (
        "making up, steps come no closer than the factor allows"
    )
    assert max(after[:5]) <= 0.005 / CATCH_UP_FACTOR + 2e-5, "right after the hold the world runs faster"


def test_a_long_stall_restarts_the_schedule_instead_of_rushing() -> None:
    pacer = StepPacer(0.01, 2.0, None, 0.0)
    steps = _run(pacer, 1.0 + CATCH_UP_LIMIT_S + 1.0, stall=(0.5, CATCH_UP_LIMIT_S + 0.5))
    resumed = [t for t in steps if t >= 0.5]
    # after the stall: back on a 5 ms schedule from where it resumed, nothing to make up
    assert len(resumed) == pytest.approx((steps[-1] - resumed[0]) / 0.005 + 1, abs=1)


def test_flat_out_steps_at_once_and_still_waits_for_a_late_driver() -> None:
    pacer = StepPacer(0.01, "max", DriverPacer(PARAMS), 0.0)
    assert pacer.tick(0.0, 0.0, lambda: [Driver("r1", 0.0, moving=True)]).step
    assert not pacer.tick(0.0, 1.0, lambda: [Driver("r1", 0.0, moving=True)]).step


def test_late_wake_ups_do_not_slow_a_high_target_rate() -> None:
    # 30x: a step every 0.33 ms; each sleep wakes 0.15 ms late and each step takes 0.1 ms (a busy machine)
    pacer = StepPacer(0.01, 30.0, DriverPacer(PARAMS), 0.0)
    steps = _run(pacer, 2.0, oversleep_s=0.00015, step_cost_s=0.0001)
    assert len(steps) == pytest.approx(6000, rel=0.01), "the schedule absorbs late wake-ups"
