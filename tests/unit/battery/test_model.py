"""The battery model: drain by load, charge on the dock, the voltage curve, overrides."""

from __future__ import annotations

import math
import random

import pytest

from services.battery.model import (
    FULL_THRESHOLD,
    TAPER_END_FRACTION,
    BatteryModel,
    BatteryParams,
    PowerSupplyStatus,
)

PARAMS = BatteryParams(
    capacity_ah=2.0,
    base_current_a=0.4,
    linear_current_a_per_mps=2.0,
    angular_current_a_per_radps=0.5,
    charge_rate_c=0.5,
    taper_start_fraction=0.8,
    empty_voltage_v=9.0,
    nominal_voltage_v=11.1,
    full_voltage_v=12.6,
    internal_resistance_ohm=0.05,
)


def test_base_load_drains_capacity_by_coulomb_counting() -> None:
    battery = BatteryModel(PARAMS, percentage=1.0)
    battery.step(3600.0, 0.0, 0.0, mated=False)
    # 0.4 A for an hour out of 2 Ah is a fifth of the charge.
    assert battery.percentage == pytest.approx(0.8)
    assert battery.current_a == pytest.approx(-0.4)
    assert battery.status is PowerSupplyStatus.DISCHARGING
    assert battery.charge_ah == pytest.approx(1.6)


def test_motion_adds_drain_in_proportion_to_speed_and_turn_rate() -> None:
    standing = BatteryModel(PARAMS, percentage=0.9)
    moving = BatteryModel(PARAMS, percentage=0.9)
    standing.step(60.0, 0.0, 0.0, mated=False)
    moving.step(60.0, -0.5, 1.0, mated=False)  # reversing drains as much as driving forward
    assert moving.current_a == pytest.approx(-(0.4 + 2.0 * 0.5 + 0.5 * 1.0))
    assert moving.percentage < standing.percentage
    drop_standing = 0.9 - standing.percentage
    drop_moving = 0.9 - moving.percentage
    assert drop_moving / drop_standing == pytest.approx(1.9 / 0.4)


def test_drain_scale_speeds_up_the_charge_but_not_the_reported_current() -> None:
    normal = BatteryModel(PARAMS, percentage=0.5)
    fast = BatteryModel(PARAMS, percentage=0.5, drain_scale=30.0)
    normal.step(10.0, 0.0, 0.0, mated=False)
    fast.step(10.0, 0.0, 0.0, mated=False)
    assert (0.5 - fast.percentage) == pytest.approx(30.0 * (0.5 - normal.percentage))
    assert fast.current_a == normal.current_a


def test_demo_scale_crosses_a_quarter_within_seconds() -> None:
    """From just above 0.25, a demo's drain scale crosses below it in well under 20 s, once, downwards."""
    battery = BatteryModel(PARAMS, percentage=0.26, drain_scale=20.0)
    previous, crossings, elapsed_s = battery.percentage, 0, 0.0
    while elapsed_s < 20.0:
        battery.step(0.1, 0.2, 0.0, mated=False)
        elapsed_s += 0.1
        if previous >= 0.25 > battery.percentage:
            crossings += 1
            crossed_at_s = elapsed_s
        previous = battery.percentage
    assert crossings == 1
    assert 1.0 < crossed_at_s < 20.0


def test_charges_while_mated_with_constant_current() -> None:
    battery = BatteryModel(PARAMS, percentage=0.5)
    battery.step(360.0, 0.0, 0.0, mated=True)
    # 0.5 C of 2 Ah is 1 A: a tenth of an hour adds 0.1 Ah, 5 %.
    assert battery.percentage == pytest.approx(0.55)
    assert battery.current_a == pytest.approx(1.0)
    assert battery.status is PowerSupplyStatus.CHARGING


def test_charge_current_tapers_near_full_and_reaches_full() -> None:
    battery = BatteryModel(PARAMS, percentage=0.85)
    battery.step(0.0, 0.0, 0.0, mated=True)
    assert TAPER_END_FRACTION * 1.0 <= battery.current_a < 1.0
    for _ in range(100_000):
        if battery.status is PowerSupplyStatus.FULL:
            break
        battery.step(1.0, 0.0, 0.0, mated=True)
    assert battery.status is PowerSupplyStatus.FULL
    assert battery.percentage >= FULL_THRESHOLD
    assert battery.current_a == 0.0
    held = battery.percentage
    battery.step(600.0, 0.0, 0.0, mated=True)  # the dock powers the robot: a full battery stays full
    assert battery.percentage == held
    assert battery.status is PowerSupplyStatus.FULL


def test_full_only_while_mated() -> None:
    battery = BatteryModel(PARAMS, percentage=1.0)
    battery.step(1.0, 0.0, 0.0, mated=False)
    assert battery.status is PowerSupplyStatus.DISCHARGING
    battery.step(1.0, 0.0, 0.0, mated=True)
    assert battery.status is PowerSupplyStatus.FULL


def test_percentage_stays_within_zero_and_one() -> None:
    battery = BatteryModel(PARAMS, percentage=0.001)
    battery.step(3600.0, 1.0, 1.0, mated=False)
    assert battery.percentage == 0.0
    battery.set_state(percentage=0.99)
    battery.step(3600.0, 0.0, 0.0, mated=True)
    assert battery.percentage == 1.0


def test_charge_is_monotone_off_and_on_the_dock() -> None:
    """Law: off the dock the charge never rises, on it never falls, whatever the motion."""
    rng = random.Random(7)
    battery = BatteryModel(PARAMS, percentage=0.5, drain_scale=50.0, charge_scale=50.0)
    for _ in range(2000):
        mated = rng.random() < 0.5
        before = battery.percentage
        battery.step(rng.uniform(0.0, 0.5), rng.uniform(-1.0, 1.0), rng.uniform(-2.0, 2.0), mated)
        assert (battery.percentage >= before) if mated else (battery.percentage <= before)
        assert 0.0 <= battery.percentage <= 1.0
        assert (battery.current_a >= 0.0) if mated else (battery.current_a < 0.0)


def test_open_circuit_voltage_is_monotone_and_hits_its_corners() -> None:
    grid = [i / 200 for i in range(201)]
    volts = [PARAMS.open_circuit_voltage_v(p) for p in grid]
    assert all(b > a for a, b in zip(volts, volts[1:], strict=False))
    assert PARAMS.open_circuit_voltage_v(0.0) == pytest.approx(9.0)
    assert PARAMS.open_circuit_voltage_v(0.5) == pytest.approx(11.1)
    assert PARAMS.open_circuit_voltage_v(1.0) == pytest.approx(12.6)


def test_terminal_voltage_sags_under_load_and_rises_while_charging() -> None:
    battery = BatteryModel(PARAMS, percentage=0.6)
    rest_v = PARAMS.open_circuit_voltage_v(0.6)
    battery.step(0.0, 0.5, 0.0, mated=False)
    assert battery.voltage_v == pytest.approx(rest_v - 1.4 * 0.05)
    battery.step(0.0, 0.0, 0.0, mated=True)
    assert battery.voltage_v == pytest.approx(rest_v + 1.0 * 0.05)


@pytest.mark.parametrize("bad", [1.5, -0.1, math.nan, math.inf, True])
def test_set_state_refuses_a_percentage_outside_zero_to_one(bad: float) -> None:
    battery = BatteryModel(PARAMS, percentage=0.7)
    with pytest.raises(ValueError, match="percentage must be within"):
        battery.set_state(percentage=bad)
    assert battery.percentage == 0.7


def test_set_state_changes_nothing_when_any_field_is_bad() -> None:
    battery = BatteryModel(PARAMS, percentage=0.7)
    with pytest.raises(ValueError, match="drain_scale"):
        battery.set_state(percentage=0.3, drain_scale=-1.0)
    assert battery.percentage == 0.7
    assert battery.drain_scale == 1.0


def test_set_state_sets_what_is_given_and_keeps_the_rest() -> None:
    battery = BatteryModel(PARAMS, percentage=0.7, charge_scale=3.0)
    battery.set_state(percentage=0.26, drain_scale=40.0)
    assert (battery.percentage, battery.drain_scale, battery.charge_scale) == (0.26, 40.0, 3.0)


def test_frozen_holds_the_percentage_but_reports_the_current() -> None:
    battery = BatteryModel(PARAMS, percentage=0.4)
    battery.set_state(frozen=True)
    battery.step(3600.0, 1.0, 0.0, mated=False)
    assert battery.percentage == 0.4
    assert battery.current_a == pytest.approx(-2.4)
    battery.step(3600.0, 0.0, 0.0, mated=True)
    assert battery.percentage == 0.4
    assert battery.status is PowerSupplyStatus.CHARGING
    battery.set_state(frozen=False)
    battery.step(360.0, 0.0, 0.0, mated=True)
    assert battery.percentage == pytest.approx(0.45)


def test_step_refuses_a_negative_or_non_finite_dt() -> None:
    battery = BatteryModel(PARAMS)
    for bad in (-0.1, math.nan, math.inf):
        with pytest.raises(ValueError, match="dt_s"):
            battery.step(bad, 0.0, 0.0, mated=False)


@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"capacity_ah": 0.0}, "capacity_ah"),
        ({"charge_rate_c": -1.0}, "charge_rate_c"),
        ({"base_current_a": math.nan}, "base_current_a"),
        ({"taper_start_fraction": 1.0}, "taper_start_fraction"),
        ({"nominal_voltage_v": 13.0}, "voltages must rise"),
    ],
)
def test_params_name_the_bad_field(changes: dict[str, float], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        BatteryParams(**changes)
