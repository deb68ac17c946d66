"""A simulated battery for a zendock stack, written from zendock's contracts alone (see ``../wire.py``).

It takes the place of ``python -m services.battery``:

- subscribes ``<ns>/odom`` (nav_msgs/Odometry: the faster the robot moves, the more current it draws),
  ``<ns>/dock_contact`` (zendock_msgs/DockContact: the dock charges the battery while ``mated``) and,
  with ``-p use_sim_time=true``, ``<ns>/clock`` (the charge is integrated on the simulator's time, so a
  simulator running 4x faster drains it 4x faster in wall time, as it should);
- publishes ``<ns>/battery_status`` (sensor_msgs/BatteryState, every field) at 10 Hz of the node's clock;
- serves ``<ns>/battery/set_state`` (zendock_msgs/srv/SetBatteryState: NaN leaves a value as it is), the
  request ``zendock demo`` and ``zendock battery`` use.

Run:  python examples/battery/battery.py -p use_sim_time=true [-p initial_percentage=0.8] [--connect ENDPOINT]
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # the examples' wire.py

from wire import BadMessage, Msg, Node, exact_fields, get, header, parse_options

#: sensor_msgs/BatteryState constants (the values ROS 2 defines).
CHARGING, DISCHARGING, FULL = 1, 2, 4
HEALTH_GOOD, TECHNOLOGY_LION = 1, 2
PUBLISH_PERIOD_S = 0.1
#: An input older than this counts as absent: no odometry is standing still, no contact is not mated.
INPUT_TIMEOUT_S = 1.0
#: A clock step longer than this is a leap (a paused or restarted simulator), not time to integrate.
MAX_STEP_S = 2.0
FULL_AT = 0.999


class Battery:
    """Coulomb counting: a 2 Ah pack drains by a base current plus a share of the speed, charges at 0.5 C
    on the dock (tapering above 80 % as a charger's constant-voltage phase would)."""

    capacity_ah = 2.0
    base_current_a = 0.4
    current_per_mps = 2.0
    current_per_radps = 0.5
    empty_v, nominal_v, full_v, resistance_ohm = 9.0, 11.1, 12.6, 0.05

    def __init__(self, node: Node) -> None:
        self.node = node
        p = node.params
        self.percentage = _fraction("initial_percentage", p.get("initial_percentage", 1.0))
        self.drain_scale = _scale("drain_scale", p.get("drain_scale", 1.0))
        self.charge_scale = _scale("charge_scale", p.get("charge_scale", 1.0))
        self.frozen = False
        self.current_a = -self.base_current_a
        self.status = DISCHARGING
        self.last_step_s: float | None = None
        self.motion = (0.0, 0.0, -math.inf)  # linear m/s, angular rad/s, when heard
        self.mated_at = -math.inf  # when a dock_contact last said mated
        self.publisher = node.publisher("battery_status", "sensor_msgs/msg/BatteryState")
        node.subscribe("odom", "nav_msgs/msg/Odometry", self.on_odom)
        node.subscribe("dock_contact", "zendock_msgs/msg/DockContact", self.on_contact)
        node.serve("battery/set_state", "zendock_msgs/srv/SetBatteryState", self.on_set_state)

    # --- inputs (run under the node's lock) ----------------------------------------------------

    def on_odom(self, msg: Msg) -> None:
        speed = math.hypot(get(msg, "twist.twist.linear.x", float), get(msg, "twist.twist.linear.y", float))
        self.motion = (speed, abs(get(msg, "twist.twist.angular.z", float)), self.node.now())

    def on_contact(self, msg: Msg) -> None:
        self.mated_at = self.node.now() if get(msg, "mated", bool) else -math.inf

    def on_set_state(self, request: Msg) -> Msg:
        """NaN leaves a value as it is; ``frozen`` is always applied. Everything is checked before anything
        changes, so a refused request (``reply_err`` naming the field) leaves the battery as it was."""
        exact_fields(request, ("percentage", "drain_scale", "charge_scale", "frozen"),
                     "zendock_msgs/srv/SetBatteryState_Request")
        wanted = {name: get(request, name, float, finite=False) for name in ("percentage", "drain_scale", "charge_scale")}
        frozen = get(request, "frozen", bool)
        if not math.isnan(wanted["percentage"]):
            _fraction("percentage", wanted["percentage"])
        for name in ("drain_scale", "charge_scale"):
            if not math.isnan(wanted[name]):
                _scale(name, wanted[name])
        self.step()  # the charge up to now moved with the old settings
        for name, value in wanted.items():
            if not math.isnan(value):
                setattr(self, name, value)
        self.frozen = frozen
        self.settle()
        self.node.log.info("state set: %.4f, drain x%g, charge x%g%s", self.percentage, self.drain_scale,
                           self.charge_scale, ", frozen" if frozen else "")
        state = self.publish()
        return {"state": state, "drain_scale": self.drain_scale, "charge_scale": self.charge_scale, "frozen": frozen}

    # --- the model -----------------------------------------------------------------------------

    def mated(self, now: float) -> bool:
        return 0.0 <= now - self.mated_at <= INPUT_TIMEOUT_S  # a stamp from the future: the clock went back

    def settle(self) -> None:
        """Current and status for the present charge and inputs."""
        now = self.node.now()
        linear, angular, heard_at = self.motion
        if not 0.0 <= now - heard_at <= INPUT_TIMEOUT_S:
            linear = angular = 0.0
        if not self.mated(now):
            self.current_a = -(self.base_current_a + self.current_per_mps * linear + self.current_per_radps * angular)
            self.status = DISCHARGING
        elif self.percentage >= FULL_AT:
            self.current_a, self.status = 0.0, FULL
        else:
            taper = 1.0 if self.percentage <= 0.8 else max(0.1, (1.0 - self.percentage) / 0.2)
            self.current_a, self.status = 0.5 * self.capacity_ah * taper, CHARGING

    def step(self) -> None:
        """Integrate the charge up to now. A clock that went back (a simulator reset) or leapt restarts
        the integration instead of draining the battery at once."""
        now = self.node.now()
        dt = 0.0 if self.last_step_s is None else now - self.last_step_s
        if dt < 0.0:
            self.mated_at, self.motion = -math.inf, (0.0, 0.0, -math.inf)
        self.last_step_s = now
        self.settle()
        if 0.0 < dt <= MAX_STEP_S and not self.frozen:
            scale = self.charge_scale if self.current_a > 0.0 else self.drain_scale
            self.percentage += self.current_a * scale * dt / 3600.0 / self.capacity_ah
            self.percentage = min(1.0, max(0.0, self.percentage))
            self.settle()

    def voltage(self) -> float:
        p = self.percentage
        rest = (self.empty_v + (self.nominal_v - self.empty_v) * p / 0.5 if p <= 0.5
                else self.nominal_v + (self.full_v - self.nominal_v) * (p - 0.5) / 0.5)
        return rest + self.current_a * self.resistance_ohm

    def publish(self) -> Msg:
        """sensor_msgs/BatteryState with every field (temperature unmeasured: NaN, as ROS 2 says)."""
        msg = {
            "header": header(self.node.now(), "base_link"),
            "voltage": self.voltage(), "temperature": math.nan, "current": self.current_a,
            "charge": self.percentage * self.capacity_ah, "capacity": self.capacity_ah,
            "design_capacity": self.capacity_ah, "percentage": float(self.percentage),
            "power_supply_status": self.status, "power_supply_health": HEALTH_GOOD,
            "power_supply_technology": TECHNOLOGY_LION, "present": True,
            "cell_voltage": [], "cell_temperature": [], "location": "base_link", "serial_number": "example-battery",
        }
        self.publisher.publish(msg)
        return msg

    def tick(self) -> None:
        self.step()
        self.publish()


def _fraction(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value <= 1.0:
        raise BadMessage(f"field '{name}': must be within [0, 1], got {value!r}")
    return float(value)


def _scale(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value >= 0.0):
        raise BadMessage(f"field '{name}': must be a finite number >= 0, got {value!r}")
    return float(value)


def main() -> int:
    options = parse_options("battery", "A simulated battery for a zendock stack (an example).")
    node = Node(options)
    try:
        battery = Battery(node)
    except BadMessage as exc:  # a bad -p value
        node.close()
        print(f"battery: error: {exc}", file=sys.stderr)
        return 2
    node.declare_ready()
    node.log.info("battery at %.0f%%, publishing %s every %g s of %s time", 100 * battery.percentage,
                  battery.publisher.key, PUBLISH_PERIOD_S, "sim" if node.use_sim_time else "wall")
    return node.run(PUBLISH_PERIOD_S, battery.tick)


if __name__ == "__main__":
    sys.exit(main())
