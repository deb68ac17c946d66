"""zendock's messages to rclpy's generated classes and back, by field name, recursively.

zendock's messages (:mod:`shared.messages`, :mod:`shared.interfaces`) carry ROS 2's field names and nesting,
so one converter walks any pair: an rclpy class says what it holds (``get_fields_and_field_types()``:
``double``, ``string``, ``std_msgs/Header``, ``sequence<float>``, ``double[36]``,
``sequence<geometry_msgs/TransformStamped>``...), zendock's value fills it; fields zendock does not carry
keep rclpy's defaults, fields rclpy does not know are left out. Numeric sequences go through
``array.array`` (rclpy's own storage, filled from the numpy buffer in one copy), fixed arrays through numpy.

Anything that does not fit (a value rclpy's setters refuse, a field zendock's validation refuses) is a
:class:`ConversionError` naming the field; callers refuse the message and go on.
"""

from __future__ import annotations

import array
import dataclasses
import importlib
import re
import typing
from functools import cache
from typing import Any

import numpy as np

from shared.schema import Message, MessageError

#: rosidl's primitive names -> (array.array typecode, numpy dtype).
_PRIMITIVES: dict[str, tuple[str, Any]] = {
    "boolean": ("", np.bool_),
    "octet": ("B", np.uint8),
    "char": ("B", np.uint8),
    "int8": ("b", np.int8),
    "uint8": ("B", np.uint8),
    "int16": ("h", np.int16),
    "uint16": ("H", np.uint16),
    "int32": ("i", np.int32),
    "uint32": ("I", np.uint32),
    "int64": ("q", np.int64),
    "uint64": ("Q", np.uint64),
    "float": ("f", np.float32),
    "double": ("d", np.float64),
}
_FLOATS = {"float", "double"}
_BOUNDS = {
    name: (int(np.iinfo(dtype).min), int(np.iinfo(dtype).max))
    for name, (_, dtype) in _PRIMITIVES.items()
    if name != "boolean" and name not in _FLOATS
}
_STRINGS = re.compile(r"^w?string(<=\d+)?$")
_SEQUENCE = re.compile(r"^sequence<(.+?)(?:, ?\d+)?>$")
_ARRAY = re.compile(r"^(.+)\[(\d+)\]$")


class ConversionError(ValueError):
    """A message that does not convert; the text names the field."""


@cache
def ros_class(type_name: str) -> Any:
    """The rclpy class of ``pkg/Name``, ``pkg/msg/Name`` or ``pkg/action/Name_Part`` (imported on first use)."""
    parts = type_name.split("/")
    if len(parts) == 2:
        package, name = parts
        kind = "msg"
    elif len(parts) == 3:
        package, kind, name = parts
    else:
        raise ConversionError(f"{type_name!r} is not a ROS 2 type name")
    if kind == "action" and "_" in name:
        action, _, part = name.rpartition("_")
        return getattr(getattr(importlib.import_module(f"{package}.action"), action), part)
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


@cache
def _fields(cls: type) -> tuple[tuple[str, str], ...]:
    return tuple(cls.get_fields_and_field_types().items())  # type: ignore[attr-defined]


# --- zendock -> rclpy --------------------------------------------------------------------------------


def to_ros(msg: Any, cls: type) -> Any:
    """An instance of rclpy's ``cls`` carrying ``msg``'s fields."""
    try:
        return _to_ros(msg, cls, "")
    except ConversionError:
        raise
    except (AssertionError, TypeError, ValueError, OverflowError, AttributeError) as exc:
        raise ConversionError(
            f"{type(msg).__name__} does not fit {cls.__name__}: {exc or type(exc).__name__}"
        ) from None


def _to_ros(msg: Any, cls: type, path: str) -> Any:
    out = cls()
    for name, ros_type in _fields(cls):
        if not hasattr(msg, name):
            continue
        value = getattr(msg, name)
        if value is None:
            continue
        where = f"{path}.{name}" if path else name
        try:
            setattr(out, name, _to_field(value, ros_type, where))
        except ConversionError:
            raise
        except (AssertionError, TypeError, ValueError, OverflowError) as exc:
            raise ConversionError(
                f"{cls.__name__}.{where} ({ros_type}): {exc or 'refused by rclpy'}"
            ) from None
    return out


def _to_field(value: Any, ros_type: str, where: str) -> Any:
    if ros_type in _PRIMITIVES:
        if ros_type == "boolean":
            return bool(value)
        if ros_type in _FLOATS:
            return float(value)
        number = int(value)
        # rclpy checks ranges only when ROS_PYTHON_CHECK_FIELDS says so; the C conversion at publish time would
        # fail outside the face's handlers, so the bounds are checked here
        low, high = _BOUNDS[ros_type]
        if not low <= number <= high:
            raise ConversionError(f"{where} ({ros_type}): {number} is out of [{low}, {high}]")
        return number
    if _STRINGS.match(ros_type):
        return str(value)
    sequence = _SEQUENCE.match(ros_type)
    fixed = _ARRAY.match(ros_type) if sequence is None else None
    if sequence is not None or fixed is not None:
        item = (sequence or fixed).group(1)  # type: ignore[union-attr]
        if item in _PRIMITIVES:
            typecode, dtype = _PRIMITIVES[item]
            data = np.ascontiguousarray(np.asarray(value, dtype=dtype).reshape(-1))
            if fixed is not None:
                return data
            if not typecode:
                return [bool(v) for v in data]
            out = array.array(typecode)
            out.frombytes(data.tobytes())
            return out
        if _STRINGS.match(item):
            return [str(v) for v in value]
        cls = ros_class(item)
        return [_to_ros(v, cls, f"{where}[{i}]") for i, v in enumerate(value)]
    return _to_ros(value, ros_class(ros_type), where)


# --- rclpy -> zendock --------------------------------------------------------------------------------


def from_ros(ros_msg: Any, zendock_type: type[Message]) -> Any:
    """A validated zendock message from an rclpy one: the fields zendock carries (those rclpy has and zendock
    does not, such as ``Range.variance``, are left; ``from_dict`` names a field zendock misses)."""
    try:
        return zendock_type.from_dict(_carried(ros_msg, zendock_type))
    except MessageError as exc:
        raise ConversionError(str(exc)) from None
    except (TypeError, ValueError, AttributeError) as exc:
        raise ConversionError(
            f"{type(ros_msg).__name__} does not fit {zendock_type.__name__}: {exc}"
        ) from None


def _carried(ros_msg: Any, zendock_type: type[Message]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    # A class is hashable; mypy reads a dataclass's instance __hash__ (None) as the class's.
    for name, hint in _hints(zendock_type):  # type: ignore[arg-type]
        if hasattr(ros_msg, name):
            out[name] = _carried_value(getattr(ros_msg, name), hint)
    return out


def _carried_value(value: Any, hint: Any) -> Any:
    if isinstance(hint, type) and issubclass(hint, Message):
        return _carried(value, hint)
    if typing.get_origin(hint) is list:
        (item,) = typing.get_args(hint) or (Any,)
        if isinstance(item, type) and issubclass(item, Message):
            return [_carried(v, item) for v in value]
        return [_plain(v) for v in value]
    return _plain(value)


def _plain(value: Any) -> Any:
    """A leaf of an rclpy message as ``Message.from_dict`` takes it (numeric storage as numpy arrays)."""
    if isinstance(value, array.array):
        return np.frombuffer(value, dtype=np.dtype(value.typecode)).copy()
    if isinstance(value, bytes):
        return np.frombuffer(value, dtype=np.uint8).copy()
    if hasattr(value, "get_fields_and_field_types"):
        return {name: _plain(getattr(value, name)) for name, _ in _fields(type(value))}  # type: ignore[arg-type]
    return value


@cache
def _hints(zendock_type: type[Message]) -> tuple[tuple[str, Any], ...]:
    hints = typing.get_type_hints(zendock_type, include_extras=False)
    return tuple((f.name, hints[f.name]) for f in dataclasses.fields(zendock_type))  # type: ignore[arg-type]
