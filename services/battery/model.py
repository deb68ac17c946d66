"""A battery by coulomb counting: load current drains it, the dock's charger fills it.

Sign convention as in sensor_msgs/BatteryState: ``current_a`` is negative while discharging and
positive while charging. The load is a base current (electronics) plus a share proportional to the
robot's speed and turn rate; while the contacts are mated the dock powers the robot and charges the
battery with constant current, then a taper as the charger's constant-voltage phase would give
(Li-ion CC-CV charging, Battery University BU-409), ending at a tenth of the constant current.

The terminal voltage is a piecewise-linear open-circuit curve (empty, nominal at half charge, full)
plus the drop (or rise) over the internal resistance. ``drain_scale`` and ``charge_scale`` are demo
knobs: the charge changes that many times faster than the current would change it, while the current
and voltage reported stay physical.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntEnum

#: At or above this fraction a battery on the dock counts as full.
FULL_THRESHOLD = 0.999
#: The charger ends its constant-voltage phase at this fraction of the constant current.
TAPER_END_FRACTION = 0.1
SECONDS_PER_HOUR = 3600.0


class PowerSupplyStatus(IntEnum):
    """The subset of sensor_msgs/BatteryState's power_supply_status this model reports (same values)."""

    CHARGING = 1
    DISCHARGING = 2
    FULL = 4


def _require(condition: bool, text: str) -> None:
    if not condition:
        raise ValueError(text)


@dataclass(frozen=True, slots=True)
class BatteryParams:
    """The battery's fixed properties. Raises ``ValueError`` naming the bad field."""

    capacity_ah: float = 2.0
    #: Drawn whenever the robot is off the dock (computer, sensors).
    base_current_a: float = 0.4
    #: Extra drain per m/s of linear speed.
    linear_current_a_per_mps: float = 2.0
    #: Extra drain per rad/s of turn rate.
    angular_current_a_per_radps: float = 0.5
    #: Constant charging current as a multiple of the capacity (C-rate).
    charge_rate_c: float = 0.5
    #: Above this fraction the charging current tapers off linearly.
    taper_start_fraction: float = 0.8
    empty_voltage_v: float = 9.0
    nominal_voltage_v: float = 11.1
    full_voltage_v: float = 12.6
    internal_resistance_ohm: float = 0.05

    def __post_init__(self) -> None:
        for name in ("capacity_ah", "charge_rate_c"):
            value = getattr(self, name)
            _require(math.isfinite(value) and value > 0.0, f"{name} must be a positive number, got {value!r}")
        for name in (
            "base_current_a",
            "linear_current_a_per_mps",
            "angular_current_a_per_radps",
            "internal_resistance_ohm",
            "empty_voltage_v",
        ):
            value = getattr(self, name)
            _require(math.isfinite(value) and value >= 0.0, f"{name} must be >= 0, got {value!r}")
        _require(
            0.0 < self.taper_start_fraction < 1.0,
            f"taper_start_fraction must be within (0, 1), got {self.taper_start_fraction!r}",
        )
        _require(
            math.isfinite(self.full_voltage_v)
            and self.empty_voltage_v < self.nominal_voltage_v < self.full_voltage_v,
            "voltages must rise from empty to nominal to full, got "
            f"empty_voltage_v={self.empty_voltage_v}, nominal_voltage_v={self.nominal_voltage_v}, "
            f"full_voltage_v={self.full_voltage_v}",
        )

    @property
    def charge_current_a(self) -> float:
        """The constant-current phase's charging current."""
        return self.charge_rate_c * self.capacity_ah

    def open_circuit_voltage_v(self, percentage: float) -> float:
        """Rest voltage at a state of charge: linear from empty to nominal (at 0.5) to full."""
        p = min(1.0, max(0.0, percentage))
        if p <= 0.5:
            return self.empty_voltage_v + (self.nominal_voltage_v - self.empty_voltage_v) * (p / 0.5)
        return self.nominal_voltage_v + (self.full_voltage_v - self.nominal_voltage_v) * ((p - 0.5) / 0.5)

    def terminal_voltage_v(self, percentage: float, current_a: float) -> float:
        """Voltage at the terminals: sags while discharging, rises while charging."""
        return self.open_circuit_voltage_v(percentage) + current_a * self.internal_resistance_ohm

    def discharge_current_a(self, linear_speed_mps: float, angular_speed_radps: float) -> float:
        """The load current off the dock (negative)."""
        return -(
            self.base_current_a
            + self.linear_current_a_per_mps * abs(linear_speed_mps)
            + self.angular_current_a_per_radps * abs(angular_speed_radps)
        )

    def charging_current_a(self, percentage: float) -> float:
        """The charger's current (positive): constant, then tapering above ``taper_start_fraction``."""
        if percentage <= self.taper_start_fraction:
            return self.charge_current_a
        remaining = (1.0 - percentage) / (1.0 - self.taper_start_fraction)
        return self.charge_current_a * max(TAPER_END_FRACTION, remaining)


def _check_fraction(name: str, value: float) -> float:
    _require(
        isinstance(value, (int, float)) and not isinstance(value, bool) and 0.0 <= value <= 1.0,
        f"{name} must be within [0, 1], got {value!r}",
    )
    return float(value)


def _check_scale(name: str, value: float) -> float:
    _require(
        isinstance(value, (int, float))
        and not isinstance(value, bool)
        and math.isfinite(value)
        and value >= 0.0,
        f"{name} must be a finite number >= 0, got {value!r}",
    )
    return float(value)


@dataclass
class BatteryModel:
    """The battery's state and its latest inputs; :meth:`step` advances it, :meth:`set_state` overrides it.

    ``current_a`` and ``status`` describe the battery now, for the inputs of the last step.
    ``frozen`` holds the percentage where it is (the current and status still follow the inputs).
    """

    params: BatteryParams = field(default_factory=BatteryParams)
    percentage: float = 1.0
    drain_scale: float = 1.0
    charge_scale: float = 1.0
    frozen: bool = False
    mated: bool = False
    linear_speed_mps: float = 0.0
    angular_speed_radps: float = 0.0
    current_a: float = field(init=False, default=0.0)
    status: PowerSupplyStatus = field(init=False, default=PowerSupplyStatus.DISCHARGING)

    def __post_init__(self) -> None:
        self.percentage = _check_fraction("percentage", self.percentage)
        self.drain_scale = _check_scale("drain_scale", self.drain_scale)
        self.charge_scale = _check_scale("charge_scale", self.charge_scale)
        self._settle()

    @property
    def charge_ah(self) -> float:
        return self.percentage * self.params.capacity_ah

    @property
    def voltage_v(self) -> float:
        return self.params.terminal_voltage_v(self.percentage, self.current_a)

    def step(self, dt_s: float, linear_speed_mps: float, angular_speed_radps: float, mated: bool) -> None:
        """Advance ``dt_s`` seconds with these inputs held over the step (explicit Euler on the charge)."""
        _require(math.isfinite(dt_s) and dt_s >= 0.0, f"dt_s must be a finite number >= 0, got {dt_s!r}")
        self.mated = bool(mated)
        self.linear_speed_mps = linear_speed_mps
        self.angular_speed_radps = angular_speed_radps
        current_a = self._current_a()
        scale = self.charge_scale if current_a > 0.0 else self.drain_scale
        if not self.frozen:
            delta = current_a * scale * dt_s / SECONDS_PER_HOUR / self.params.capacity_ah
            self.percentage = min(1.0, max(0.0, self.percentage + delta))
        self._settle()

    def set_state(
        self,
        percentage: float | None = None,
        drain_scale: float | None = None,
        charge_scale: float | None = None,
        frozen: bool | None = None,
    ) -> None:
        """Override what is given (``None`` keeps it). Checks everything before changing anything."""
        new_percentage = self.percentage if percentage is None else _check_fraction("percentage", percentage)
        new_drain = self.drain_scale if drain_scale is None else _check_scale("drain_scale", drain_scale)
        new_charge = self.charge_scale if charge_scale is None else _check_scale("charge_scale", charge_scale)
        self.percentage, self.drain_scale, self.charge_scale = new_percentage, new_drain, new_charge
        if frozen is not None:
            self.frozen = bool(frozen)
        self._settle()

    def _current_a(self) -> float:
        if not self.mated:
            return self.params.discharge_current_a(self.linear_speed_mps, self.angular_speed_radps)
        if self.percentage >= FULL_THRESHOLD:
            return 0.0
        return self.params.charging_current_a(self.percentage)

    def _settle(self) -> None:
        """Current and status for the present charge and inputs."""
        self.current_a = self._current_a()
        if not self.mated:
            self.status = PowerSupplyStatus.DISCHARGING
        elif self.percentage >= FULL_THRESHOLD:
            self.status = PowerSupplyStatus.FULL
        else:
            self.status = PowerSupplyStatus.CHARGING
