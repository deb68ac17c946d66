"""Run by ``.venv-ros2/bin/python``: every message the DDS face carries, zendock -> rclpy -> zendock.

For each route of :mod:`shared.ros2.bridge_routes` and each action part, a zendock message with every field
filled (numbers, strings, arrays, nested messages, lists of them) goes to rclpy's class and back; the round
trip must give the same message. Also: what rclpy refuses, and what zendock's validation refuses, raise
ConversionError. One JSON line per case on stdout.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import typing
from typing import Any

import numpy as np

from services.ros2_dds.convert import ConversionError, from_ros, ros_class, to_ros
from shared.messages import Twist
from shared.ros2.bridge_routes import ACTIONS, INBOUND, TOPICS, TWIST_STAMPED
from shared.schema import Message


def filled(cls: type[Message], seed: int = 1) -> Message:
    """``cls`` with every field set to something that is not its default."""
    hints = typing.get_type_hints(cls, include_extras=False)
    values: dict[str, Any] = {}
    for i, f in enumerate(dataclasses.fields(cls)):  # type: ignore[arg-type]
        hint, current = hints[f.name], getattr(cls(), f.name)
        values[f.name] = _value(hint, current, seed + i)
    try:
        return cls(**values)
    except Exception:  # a field with a narrower range than the sample: leave the defaults
        return cls()


def _value(hint: Any, current: Any, seed: int) -> Any:
    if isinstance(hint, type) and issubclass(hint, Message):
        return filled(hint, seed)
    if typing.get_origin(hint) is list:
        (item,) = typing.get_args(hint)
        if isinstance(item, type) and issubclass(item, Message):
            return [filled(item, seed), filled(item, seed + 1)]
        if item is str:
            return ["a", "b"]
        return [float(seed), float(seed + 1)] if item is float else [seed, seed + 1]
    if isinstance(current, np.ndarray):
        if current.size:
            return (np.arange(current.size) % 7).astype(current.dtype).reshape(current.shape)
        return np.arange(3).astype(current.dtype)
    if isinstance(current, bool):
        return not current
    if isinstance(current, int):
        return type(current)(1) if hasattr(type(current), "__members__") else 1
    if isinstance(current, float):  # within [0, 1]: percentages and fractions take it
        return 0.25 + (seed % 3) * 0.25
    if isinstance(current, str):
        return f"s{seed}"
    return current


def same(a: Any, b: Any) -> bool:
    return a.encode() == b.encode()


def check(name: str, zendock_type: type[Message], ros_type: str) -> None:
    cls = ros_class(ros_type)
    for label, msg in (("default", zendock_type()), ("filled", filled(zendock_type))):
        try:
            back = from_ros(to_ros(msg, cls), zendock_type)
            ok, detail = same(msg, back), ""
        except ConversionError as exc:
            ok, detail = False, str(exc)
        print(json.dumps({"case": f"{name} {label}", "ok": ok, "detail": detail}), flush=True)


def main() -> int:
    for route in TOPICS:
        check(route.ros_topic, route.zendock_type, route.ros_type)
    for inbound in INBOUND:
        if inbound.ros_type != TWIST_STAMPED:
            check(f"in {inbound.ros_topic}", inbound.zendock_type, inbound.ros_type)
    for action in ACTIONS:
        for part, zendock_type in (
            ("Goal", action.zendock.goal),
            ("Result", action.zendock.result),
            ("Feedback", action.zendock.feedback),
        ):
            check(f"{action.name} {part}", zendock_type, f"{action.ros_type}_{part}")
    # Refused: a velocity zendock's validation does not take, a value rclpy's setter does not take.
    broken = ros_class("geometry_msgs/msg/Twist")()
    broken.linear.x = math.nan
    for label, attempt in (
        ("nan twist", lambda: from_ros(broken, Twist)),
        (
            "uint16 overflow",
            lambda: to_ros(
                ACTIONS[0].zendock.result(error_code=1 << 20), ros_class(f"{ACTIONS[0].ros_type}_Result")
            ),
        ),
    ):
        try:
            attempt()
            print(json.dumps({"case": f"refuses {label}", "ok": False, "detail": "converted"}), flush=True)
        except ConversionError as exc:
            print(json.dumps({"case": f"refuses {label}", "ok": True, "detail": str(exc)}), flush=True)
        except Exception as exc:  # anything else would escape the face's handlers
            print(json.dumps({"case": f"refuses {label}", "ok": False, "detail": repr(exc)}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
