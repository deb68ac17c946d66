"""The battery service's wiring: odometry and dock contact in, ``battery_status`` out, a set-state request.

Subscribes ``odom`` (nav_msgs/Odometry: the twist gives the motion load) and ``dock_contact``
(zendock_msgs/DockContact: charging while ``mated``); publishes ``battery_status``
(sensor_msgs/BatteryState) every ``1 / publish_rate_hz`` seconds on the node's clock and right after a
``battery/set_state`` request. The charge is integrated over the clock's steps at each publication;
a clock that jumps back (simulator reset) or leaps forward restarts the integration instead of
draining the battery at once. An input silent for longer than its timeout counts as absent: no dock
contact means not mated, no odometry means standing still.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Annotated

from msgspec import Meta

from services.battery.model import BatteryModel, BatteryParams
from services.battery.state_file import StoredCharge, load_charge, save_charge
from services.battery.timekeeping import FreshValue, StepClock
from shared import topics
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest, SetBatteryStateResponse
from shared.messages import BatteryState, DockContact, Header, Odometry
from shared.node import RELIABLE, SENSOR_DATA, Node, QoS
from shared.parameters import ServiceParams, runtime_settable
from shared.runtime import ServiceSpec

#: How often the node says it is still waiting for the simulator's clock.
CLOCK_WAIT_LOG_PERIOD_S = 5.0
#: Write the charge to the state file at most this often (wall seconds); a set_state request writes at once.
STATE_SAVE_PERIOD_S = 0.5


class Params(ServiceParams):
    """Parameters of ``python -m services.battery`` (``-p name=value`` or a YAML file)."""

    capacity_ah: Annotated[float, Meta(gt=0.0, description="capacity in ampere-hours")] = 2.0
    initial_percentage: Annotated[
        float, Meta(ge=0.0, le=1.0, description="state of charge at start, 0..1")
    ] = 1.0
    base_current_a: Annotated[
        float, Meta(ge=0.0, description="drain off the dock while standing still, A")
    ] = 0.4
    linear_current_a_per_mps: Annotated[
        float, Meta(ge=0.0, description="extra drain per m/s of linear speed, A")
    ] = 2.0
    angular_current_a_per_radps: Annotated[
        float, Meta(ge=0.0, description="extra drain per rad/s of turn rate, A")
    ] = 0.5
    charge_rate_c: Annotated[
        float, Meta(gt=0.0, description="constant charging current as a multiple of capacity")
    ] = 0.5
    taper_start_fraction: Annotated[
        float, Meta(gt=0.0, lt=1.0, description="charge above which the current tapers")
    ] = 0.8
    empty_voltage_v: Annotated[float, Meta(ge=0.0, description="open-circuit voltage when empty")] = 9.0
    nominal_voltage_v: Annotated[float, Meta(gt=0.0, description="open-circuit voltage at half charge")] = (
        11.1
    )
    full_voltage_v: Annotated[float, Meta(gt=0.0, description="open-circuit voltage when full")] = 12.6
    internal_resistance_ohm: Annotated[
        float, Meta(ge=0.0, description="series resistance: voltage sag under load")
    ] = 0.05
    drain_scale: Annotated[
        float,
        Meta(
            ge=0.0,
            description="demo knob: the charge drains this many times faster",
            extra=runtime_settable(),
        ),
    ] = 1.0
    charge_scale: Annotated[
        float,
        Meta(
            ge=0.0, description="demo knob: the charge fills this many times faster", extra=runtime_settable()
        ),
    ] = 1.0
    frozen: Annotated[
        bool,
        Meta(description="hold the charge where it is (neither drains nor fills)", extra=runtime_settable()),
    ] = False
    state_file: Annotated[
        str,
        Meta(description="keep the charge in this file across restarts (empty: start from the parameters)"),
    ] = ""
    publish_rate_hz: Annotated[
        float, Meta(ge=1.0, le=100.0, description="battery_status rate on the node's clock")
    ] = 10.0
    dock_contact_timeout_s: Annotated[
        float, Meta(gt=0.0, description="older dock_contact counts as not mated")
    ] = 1.0
    odom_timeout_s: Annotated[float, Meta(gt=0.0, description="older odometry counts as standing still")] = (
        1.0
    )
    max_step_s: Annotated[
        float, Meta(gt=0.0, description="clock steps longer than this are skipped (a leap)")
    ] = 2.0
    frame_id: Annotated[str, Meta(description="header.frame_id of battery_status")] = "base_link"

    def __post_init__(self) -> None:
        self.battery_params()  # raises ValueError naming the field
        if self.max_step_s <= 1.0 / self.publish_rate_hz:
            raise ValueError(
                f"max_step_s ({self.max_step_s}) must exceed the publication period ({1.0 / self.publish_rate_hz:g} s)"
            )

    def battery_params(self) -> BatteryParams:
        return BatteryParams(
            capacity_ah=self.capacity_ah,
            base_current_a=self.base_current_a,
            linear_current_a_per_mps=self.linear_current_a_per_mps,
            angular_current_a_per_radps=self.angular_current_a_per_radps,
            charge_rate_c=self.charge_rate_c,
            taper_start_fraction=self.taper_start_fraction,
            empty_voltage_v=self.empty_voltage_v,
            nominal_voltage_v=self.nominal_voltage_v,
            full_voltage_v=self.full_voltage_v,
            internal_resistance_ohm=self.internal_resistance_ohm,
        )


def battery_state_message(model: BatteryModel, header: Header) -> BatteryState:
    """The model as sensor_msgs/BatteryState (temperature unmeasured: NaN)."""
    return BatteryState(
        header=header,
        voltage=model.voltage_v,
        current=model.current_a,
        charge=model.charge_ah,
        capacity=model.params.capacity_ah,
        design_capacity=model.params.capacity_ah,
        percentage=model.percentage,
        power_supply_status=int(model.status),
        power_supply_health=BatteryState.POWER_SUPPLY_HEALTH_GOOD,
        power_supply_technology=BatteryState.POWER_SUPPLY_TECHNOLOGY_LION,
        present=True,
        location=header.frame_id,
        serial_number="zendock-sim",
    )


def _given(value: float) -> float | None:
    """NaN in a request means "leave it as it is"."""
    return None if math.isnan(value) else value


class BatteryService:
    """The simulated battery on a node; see the module docstring for the topics."""

    def __init__(self, node: Node, params: Params) -> None:
        self._node = node
        self._params = params
        self._log = node.log
        self._model = BatteryModel(
            params.battery_params(),
            percentage=params.initial_percentage,
            drain_scale=params.drain_scale,
            charge_scale=params.charge_scale,
        )
        self._state_path = Path(params.state_file) if params.state_file else None
        self._state_saved_wall_s = 0.0
        stored = load_charge(self._state_path) if self._state_path is not None else None
        if stored is not None:
            self._model.set_state(
                percentage=stored.percentage,
                drain_scale=stored.drain_scale,
                charge_scale=stored.charge_scale,
                frozen=stored.frozen,
            )
            self._log.info("charge restored from %s: %.1f%%", params.state_file, 100.0 * stored.percentage)
            params.drain_scale, params.charge_scale = stored.drain_scale, stored.charge_scale
            params.frozen = stored.frozen
        elif params.frozen:
            self._model.set_state(frozen=True)
        self._clock = StepClock(params.max_step_s)
        self._odom: FreshValue[tuple[float, float]] = FreshValue(params.odom_timeout_s)
        self._contact: FreshValue[bool] = FreshValue(params.dock_contact_timeout_s)
        self._contact_was_fresh = False
        self._first_tick_s: float | None = None
        self._reported_no_contact = False
        self._server = node.create_service(SET_BATTERY_STATE, topics.BATTERY_SET_STATE, self._on_set_state)
        self._publisher = node.create_publisher(BatteryState, topics.BATTERY_STATUS, RELIABLE)
        self._odom_sub = node.create_subscription(Odometry, topics.ODOM, self._on_odom, SENSOR_DATA)
        self._contact_sub = node.create_subscription(
            DockContact, topics.DOCK_CONTACT, self._on_dock_contact, QoS(depth=5)
        )
        self._timer = node.create_timer(1.0 / params.publish_rate_hz, self._on_timer)
        self._clock_wait_timer = (
            node.create_timer(CLOCK_WAIT_LOG_PERIOD_S, self._on_clock_wait, wall=True)
            if node.use_sim_time
            else None
        )
        self._log.info(
            "battery %.2f Ah at %.0f%%, publishing %s at %g Hz on %s time",
            params.capacity_ah,
            100.0 * params.initial_percentage,
            self._publisher.key,
            params.publish_rate_hz,
            "sim" if node.use_sim_time else "wall",
        )

    # --- inputs ----------------------------------------------------------------------------------

    def _on_odom(self, msg: Odometry) -> None:
        twist = msg.twist.twist
        self._odom.update(
            (math.hypot(twist.linear.x, twist.linear.y), abs(twist.angular.z)), self._node.now()
        )

    def _on_dock_contact(self, msg: DockContact) -> None:
        self._contact.update(msg.mated, self._node.now())

    def _mated(self, now_s: float) -> bool:
        """The dock contact's ``mated``, or False when it has gone silent (said once per silence)."""
        fresh = self._contact.is_fresh(now_s)
        if fresh:
            self._contact_was_fresh = True
        elif self._contact_was_fresh:
            self._contact_was_fresh = False
            self._log.warning(
                "no dock_contact for more than %g s: treating the contacts as open (not charging)",
                self._contact.timeout_s,
            )
        elif not self._contact.ever_received and not self._reported_no_contact:
            if self._first_tick_s is None or now_s < self._first_tick_s:
                self._first_tick_s = now_s
            elif now_s - self._first_tick_s > self._contact.timeout_s:
                self._reported_no_contact = True
                self._log.info("no dock_contact received yet: not charging until one says mated")
        return bool(self._contact.get(now_s, False))

    # --- integration and output ------------------------------------------------------------------

    def _advance(self) -> None:
        """Integrate the model up to now on the node's clock."""
        now_s = self._node.now()
        step = self._clock.advance(now_s)
        if step.jumped_back:
            self._log.warning("clock jumped back to %.3f s (a reset?): restarting integration", now_s)
            self._odom.forget()
            self._contact.forget()
            self._contact_was_fresh = False
        elif step.jumped_forward:
            self._log.warning(
                "clock leapt forward more than %g s: skipping that interval", self._clock.max_step_s
            )
        linear_mps, angular_radps = self._odom.get(now_s, (0.0, 0.0))
        self._model.step(step.dt_s, linear_mps, angular_radps, self._mated(now_s))

    def _publish(self) -> BatteryState:
        msg = battery_state_message(self._model, Header(self._node.now_msg(), self._params.frame_id))
        self._publisher.publish(msg)
        self._keep_charge()
        return msg

    def _keep_charge(self, force: bool = False) -> None:
        """Write the charge to the state file, at most every ``STATE_SAVE_PERIOD_S`` unless ``force``."""
        if self._state_path is None or (
            not force and time.monotonic() - self._state_saved_wall_s < STATE_SAVE_PERIOD_S
        ):
            return
        self._state_saved_wall_s = time.monotonic()
        model = self._model
        try:
            save_charge(
                self._state_path,
                StoredCharge(model.percentage, model.drain_scale, model.charge_scale, model.frozen),
            )
        except OSError as exc:
            self._log.warning("charge not saved to %s: %s", self._state_path, exc)

    def _on_timer(self) -> None:
        self._advance()
        self._publish()

    def _on_clock_wait(self) -> None:
        if self._node.clock_started:
            assert self._clock_wait_timer is not None
            self._clock_wait_timer.cancel()
            return
        self._log.warning("use_sim_time is set but no clock message has arrived yet: nothing is published")

    # --- requests --------------------------------------------------------------------------------

    def _on_set_state(self, request: SetBatteryStateRequest) -> SetBatteryStateResponse:
        self._advance()
        self._model.set_state(
            percentage=_given(request.percentage),
            drain_scale=_given(request.drain_scale),
            charge_scale=_given(request.charge_scale),
            frozen=request.frozen,
        )
        self._log.info(
            "state set: %.4f, drain x%g, charge x%g%s",
            self._model.percentage,
            self._model.drain_scale,
            self._model.charge_scale,
            ", frozen" if self._model.frozen else "",
        )
        # The parameters say what is in force (``zendock param get battery drain_scale``).
        self._params.drain_scale, self._params.charge_scale = (
            self._model.drain_scale,
            self._model.charge_scale,
        )
        self._params.frozen = self._model.frozen
        self._keep_charge(force=True)
        state = self._publish()
        return SetBatteryStateResponse(
            state=state,
            drain_scale=self._model.drain_scale,
            charge_scale=self._model.charge_scale,
            frozen=self._model.frozen,
        )

    def on_parameter_set(self, name: str, value: float | bool) -> None:
        """A runtime change of ``drain_scale``, ``charge_scale`` or ``frozen`` (``zendock param set``)
        applies at once."""
        self._advance()  # the charge up to now moved at the old rate
        if name == "drain_scale":
            self._model.set_state(drain_scale=value)
        elif name == "charge_scale":
            self._model.set_state(charge_scale=value)
        elif name == "frozen":
            self._model.set_state(frozen=bool(value))
        self._keep_charge(force=True)

    def close(self) -> None:
        self._timer.cancel()
        if self._clock_wait_timer is not None:
            self._clock_wait_timer.cancel()


SERVICE = ServiceSpec(
    "battery",
    Params,
    BatteryService,
    description="Simulated battery: publishes battery_status, drains with motion, charges on the dock.",
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
