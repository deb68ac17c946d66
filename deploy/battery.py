"""``zendock battery get|set``: the simulated battery's charge from the command line.

``get`` prints the newest ``battery_status`` (charge, status, voltage, current) and the knobs in force,
which the battery node keeps as its parameters (``drain_scale``, ``charge_scale``, ``frozen``). ``set``
calls ``battery/set_state``: a LEVEL (``0.2`` or ``20%``) and any of the knobs; whatever is not given stays
as it is (the service thaws a battery unless told ``frozen``, so ``set`` reads ``frozen`` first). A
user's own docking program can start from a low battery this way, with ``zendock param set docking
auto_dock false`` so that zendock's docking does not react to the same drop.

Exit codes: 0 done, 1 nothing answered, 2 refused or a bad argument (the reason on one line).
"""

from __future__ import annotations

import json
import math
import threading
from dataclasses import dataclass
from typing import Any, TextIO

import zenoh

from deploy.keys.connection import BusOptions, open_bus
from deploy.keys.errors import EXIT_NOT_FOUND, EXIT_USAGE, KeysError
from shared import topics
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest
from shared.interfaces.parameters import LIST_PARAMETERS, ListParametersRequest
from shared.messages import BatteryState
from shared.names import parameter_service, topic_key
from shared.node import ServiceError, ServiceUnavailable, call_service
from shared.schema import MessageError

REQUEST_TIMEOUT_S = 3.0
#: How long ``get`` waits for a ``battery_status`` (the battery publishes at 1 Hz or faster).
STATUS_WAIT_S = 5.0
BATTERY_NODE = "battery"

STATUS_NAMES = {
    BatteryState.POWER_SUPPLY_STATUS_UNKNOWN: "UNKNOWN",
    BatteryState.POWER_SUPPLY_STATUS_CHARGING: "CHARGING",
    BatteryState.POWER_SUPPLY_STATUS_DISCHARGING: "DISCHARGING",
    BatteryState.POWER_SUPPLY_STATUS_NOT_CHARGING: "NOT_CHARGING",
    BatteryState.POWER_SUPPLY_STATUS_FULL: "FULL",
}


def parse_level(text: str) -> float:
    """``0.2`` or ``20%`` -> 0.2; ValueError naming what is wrong (``20`` asks whether ``20%`` was meant)."""
    raw = text.strip()
    percent = raw.endswith("%")
    try:
        value = float(raw.removesuffix("%"))
    except ValueError:
        raise ValueError(
            f"LEVEL must be a fraction such as 0.2 or a percentage such as 20%, got {text!r}"
        ) from None
    if percent:
        value /= 100.0
    if not math.isfinite(value) or not 0.0 <= value <= 1.0:
        hint = f" (did you mean {raw}%?)" if not percent and 1.0 < value <= 100.0 else ""
        raise ValueError(f"LEVEL must be within 0..1 (0%..100%), got {text!r}{hint}")
    return value


def parse_scale(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"a scale is a number >= 0, got {text!r}") from None
    if not math.isfinite(value) or value < 0.0:
        raise ValueError(f"a scale is a number >= 0, got {text!r}")
    return value


@dataclass(frozen=True)
class BatteryReading:
    """What ``get`` shows: the battery's message and the knobs in force."""

    state: BatteryState
    drain_scale: float
    charge_scale: float
    frozen: bool

    def line(self) -> str:
        s = self.state
        knobs = f"drain x{self.drain_scale:g}, charge x{self.charge_scale:g}" + (
            ", frozen" if self.frozen else ""
        )
        return (
            f"{100.0 * s.percentage:.1f}%  {STATUS_NAMES.get(s.power_supply_status, str(s.power_supply_status))}  "
            f"{s.voltage:.2f} V  {s.current:+.2f} A  ({knobs})"
        )

    def as_json(self) -> dict[str, Any]:
        s = self.state
        return {
            "percentage": s.percentage,
            "power_supply_status": s.power_supply_status,
            "status": STATUS_NAMES.get(s.power_supply_status, "UNKNOWN"),
            "voltage": s.voltage,
            "current": s.current,
            "charge": s.charge,
            "capacity": s.capacity,
            "drain_scale": self.drain_scale,
            "charge_scale": self.charge_scale,
            "frozen": self.frozen,
        }


def _parameters(session: zenoh.Session, namespace: str) -> dict[str, Any]:
    """The battery node's parameters by name (one request: the knobs are among them)."""
    key = topic_key(namespace, parameter_service(BATTERY_NODE, "list"))
    try:
        reply = call_service(session, key, LIST_PARAMETERS, ListParametersRequest(), REQUEST_TIMEOUT_S)
    except ServiceUnavailable:
        raise KeysError(_no_battery(namespace, key), EXIT_NOT_FOUND) from None
    except ServiceError as exc:
        raise KeysError(f"battery: {str(exc).removeprefix(f'{key}: ')}", EXIT_USAGE) from None
    return {p.name: json.loads(p.value_json) for p in reply.parameters}


def _no_battery(namespace: str, key: str) -> str:
    where = f" in namespace {namespace!r}" if namespace else ""
    return f"no battery service answered{where} on {key} (is the stack up? zendock nodes list)"


def _newest_status(session: zenoh.Session, namespace: str) -> BatteryState:
    key = topic_key(namespace, topics.BATTERY_STATUS)
    arrived = threading.Event()
    got: list[BatteryState] = []

    def on_sample(sample: zenoh.Sample) -> None:
        if arrived.is_set():
            return
        try:
            got.append(BatteryState.decode(sample.payload.to_bytes()))
        except MessageError:
            return  # not a BatteryState: wait for one that is
        arrived.set()

    subscriber = session.declare_subscriber(key, on_sample)
    try:
        if not arrived.wait(STATUS_WAIT_S):
            raise KeysError(
                f"no battery_status on {key} within {STATUS_WAIT_S:g} s (is the stack up?)", EXIT_NOT_FOUND
            )
    finally:
        subscriber.undeclare()
    return got[0]


def read_battery(options: BusOptions) -> BatteryReading:
    with open_bus(options) as session:
        state = _newest_status(session, options.namespace)
        knobs = _parameters(session, options.namespace)
        return BatteryReading(
            state=state,
            drain_scale=float(knobs["drain_scale"]),
            charge_scale=float(knobs["charge_scale"]),
            frozen=bool(knobs["frozen"]),
        )


def set_battery(
    options: BusOptions,
    level: float | None,
    drain_scale: float | None,
    charge_scale: float | None,
    frozen: bool | None,
) -> BatteryReading:
    """``battery/set_state`` with what is given; the rest stays as it is."""
    key = topic_key(options.namespace, topics.BATTERY_SET_STATE)
    with open_bus(options) as session:
        keep_frozen = bool(_parameters(session, options.namespace)["frozen"]) if frozen is None else frozen
        request = SetBatteryStateRequest(
            percentage=math.nan if level is None else level,
            drain_scale=math.nan if drain_scale is None else drain_scale,
            charge_scale=math.nan if charge_scale is None else charge_scale,
            frozen=keep_frozen,
        )
        try:
            reply = call_service(session, key, SET_BATTERY_STATE, request, REQUEST_TIMEOUT_S)
        except ServiceUnavailable:
            raise KeysError(_no_battery(options.namespace, key), EXIT_NOT_FOUND) from None
        except ServiceError as exc:
            raise KeysError(f"battery: {str(exc).removeprefix(f'{key}: ')}", EXIT_USAGE) from None
    return BatteryReading(reply.state, reply.drain_scale, reply.charge_scale, reply.frozen)


def run_battery_get(options: BusOptions, as_json: bool, out: TextIO) -> int:
    reading = read_battery(options)
    out.write(json.dumps(reading.as_json()) + "\n" if as_json else reading.line() + "\n")
    return 0


def run_battery_set(
    options: BusOptions,
    level: float | None,
    drain_scale: float | None,
    charge_scale: float | None,
    frozen: bool | None,
    as_json: bool,
    out: TextIO,
) -> int:
    if level is None and drain_scale is None and charge_scale is None and frozen is None:
        raise KeysError(
            "nothing to set: give a LEVEL (0.2 or 20%) or --drain-scale, --charge-scale, --freeze, --thaw",
            EXIT_USAGE,
        )
    reading = set_battery(options, level, drain_scale, charge_scale, frozen)
    out.write(json.dumps(reading.as_json()) + "\n" if as_json else reading.line() + "\n")
    return 0
