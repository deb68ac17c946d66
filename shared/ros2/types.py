"""ROS 2 Jazzy message types on the wire: CDR bytes and RIHS01 type hashes, from rosbags' type store.

zendock's messages (:mod:`shared.messages`) mirror ROS 2's field names and nesting, so one converter
driven by the Jazzy definitions turns any of them into the ROS 2 message and back: fields zendock does
not carry get ROS 2's defaults (zero, empty), fields ROS 2 does not know are left out. rosbags writes
the CDR (little endian, with its 4-byte encapsulation header) and computes the type hashes from the
type descriptions, as rosidl does.
"""

from __future__ import annotations

import dataclasses
import typing
from functools import cache
from typing import Any, TypeVar

import numpy as np
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from shared.ros2 import interfaces
from shared.schema import Message

M = TypeVar("M", bound=Message)

#: rosbags' node kinds in a field definition.
_BASE, _NAME, _ARRAY, _SEQUENCE = 1, 2, 3, 4

_NUMPY_OF = {
    "bool": np.bool_,
    "byte": np.uint8,
    "char": np.uint8,
    "int8": np.int8,
    "uint8": np.uint8,
    "int16": np.int16,
    "uint16": np.uint16,
    "int32": np.int32,
    "uint32": np.uint32,
    "int64": np.int64,
    "uint64": np.uint64,
    "float32": np.float32,
    "float64": np.float64,
}


class Ros2TypeError(ValueError):
    """A type zendock cannot put on ROS 2's wire, or bytes that are not the type they claim."""


@cache
def typestore() -> Typestore:
    """Jazzy's message definitions and the Nav2 actions zendock serves (:mod:`shared.ros2.interfaces`), one store
    per process, with every ``char`` a ``uint8`` (:func:`_char_as_uint8`)."""
    defs: dict[str, Any] = dict(get_typestore(Stores.ROS2_JAZZY).fielddefs)
    defs.update(interfaces.definitions())
    defs = {
        name: (consts, [(field, _char_as_uint8(desc)) for field, desc in fields])
        for name, (consts, fields) in defs.items()
    }
    store = get_typestore(Stores.EMPTY)
    store.register(defs)
    return store


def _char_as_uint8(desc: Any) -> Any:
    """A field description with ``char`` read as ``uint8``, in any array or sequence.

    ROS 2's IDL maps a .msg ``char`` to ``uint8``, so rosidl's type description (and so the RIHS01 hash) of
    ``std_msgs/msg/Char``, of ``service_msgs/msg/ServiceEventInfo`` (``char[16] client_gid``) and of every
    service, whose event carries it, says ``uint8``; rosbags keeps ``char`` (its own type id). Both are one
    byte in CDR, so only the hashes change. Constants keep their type: the hash does not cover them."""
    kind, detail = desc
    if kind == _BASE and detail[0] == "char":
        return (_BASE, ("uint8", detail[1]))
    if kind in (_ARRAY, _SEQUENCE):
        sub, length = detail
        return (kind, (_char_as_uint8(sub), length))
    return desc


#: zendock names its docking actions' types after opennav_docking_msgs, where they began; Jazzy ships them
#: in nav2_msgs. The ROS 2 side always uses Jazzy's names.
_ZENDOCK_PREFIXES = (("opennav_docking_msgs/action/", "nav2_msgs/action/"),)


def jazzy_name(zendock_type: str) -> str:
    """The ROS 2 Jazzy name of a zendock message type (``opennav_docking_msgs/action/DockRobot_Goal`` ->
    ``nav2_msgs/action/DockRobot_Goal``); other names are the same in both."""
    for ours, theirs in _ZENDOCK_PREFIXES:
        if zendock_type.startswith(ours):
            return theirs + zendock_type[len(ours) :]
    return zendock_type


def zendock_name(ros_type: str) -> str:
    """The inverse of :func:`jazzy_name` for the types zendock has."""
    from shared.schema import registered_types  # noqa: PLC0415 - the registry fills as interfaces load

    for ours, theirs in _ZENDOCK_PREFIXES:
        if ros_type.startswith(theirs) and ours + ros_type[len(theirs) :] in registered_types():
            return ours + ros_type[len(theirs) :]
    return ros_type


def knows(ros_type: str) -> bool:
    return ros_type in typestore().types


@cache
def type_hash(ros_type: str) -> str:
    """``RIHS01_<sha256>`` of the type's description, as ROS 2 Jazzy announces it (messages and services)."""
    _require(ros_type)
    return typestore().hash_rihs01(ros_type)


def _require(ros_type: str) -> None:
    if not knows(ros_type):
        raise Ros2TypeError(f"{ros_type} is not a ROS 2 Jazzy message type")


# --- zendock -> ROS 2 ----------------------------------------------------------------------------


def to_ros(msg: Message | None, ros_type: str) -> Any:
    """The rosbags message of ``ros_type`` carrying ``msg``'s fields (ROS 2 defaults for the rest)."""
    _require(ros_type)
    store = typestore()
    _, fields = store.fielddefs[ros_type]
    values = {name: _value(getattr(msg, name, None), desc) for name, desc in fields}
    return store.types[ros_type](**values)


def _value(value: Any, desc: tuple[int, Any]) -> Any:
    kind, detail = desc
    if kind == _BASE:
        return _base(value, detail[0])
    if kind == _NAME:
        return to_ros(value, detail)
    sub, length = detail
    sub_kind, sub_detail = sub
    if sub_kind == _BASE and sub_detail[0] in _NUMPY_OF:
        dtype = _NUMPY_OF[sub_detail[0]]
        if value is None:
            return np.zeros(length if kind == _ARRAY else 0, dtype=dtype)
        array: np.ndarray = np.asarray(value, dtype=dtype).reshape(-1)
        if kind == _ARRAY and array.size != length:
            raise Ros2TypeError(f"a fixed array of {length} holds {array.size} items")
        return array
    items = list(value) if value is not None else []
    if kind == _ARRAY and value is None:
        items = [None] * length
    return [_value(item, sub) for item in items]


def _base(value: Any, type_name: str) -> Any:
    if type_name == "string" or type_name == "wstring":
        return "" if value is None else str(value)
    if type_name == "bool":
        return bool(value) if value is not None else False
    if type_name in ("float32", "float64"):
        return float(value) if value is not None else 0.0
    return int(value) if value is not None else 0


def to_cdr(msg: Message, ros_type: str) -> bytes:
    """``msg`` as ROS 2 CDR bytes (little endian, encapsulation header included)."""
    try:
        return bytes(typestore().serialize_cdr(to_ros(msg, ros_type), ros_type))
    except Ros2TypeError:
        raise
    except (ValueError, TypeError, OverflowError, AttributeError) as exc:
        raise Ros2TypeError(f"{type(msg).__name__} does not fit {ros_type}: {exc}") from None


# --- ROS 2 -> zendock ----------------------------------------------------------------------------


def from_cdr(payload: bytes, ros_type: str) -> Any:
    """The rosbags message in ``payload``; :class:`Ros2TypeError` for bytes that are not one."""
    _require(ros_type)
    if len(payload) < 4 or payload[0] != 0 or payload[1] not in (0, 1):
        raise Ros2TypeError(
            f"{ros_type}: not CDR (encapsulation header {bytes(payload[:4]).hex() or 'missing'})"
        )
    try:
        return typestore().deserialize_cdr(payload, ros_type)
    except Exception as exc:  # rosbags raises several unrelated types for short or garbled bytes
        raise Ros2TypeError(f"{ros_type}: malformed CDR ({type(exc).__name__}: {exc})") from None


def from_ros(ros_msg: Any, zendock_type: type[M]) -> M:
    """A validated zendock message from a rosbags one: the fields zendock carries (``MessageError`` names
    the one that does not fit; fields ROS 2 has and zendock does not, such as ``Range.variance``, are left)."""
    return zendock_type.from_dict(_carried(ros_msg, zendock_type))


def _carried(ros_msg: Any, zendock_type: type[Message]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, hint in _field_types(zendock_type).items():
        if not hasattr(ros_msg, name):
            continue  # zendock's own field: from_dict names it as missing
        out[name] = _carried_value(getattr(ros_msg, name), hint)
    return out


def _carried_value(value: Any, hint: Any) -> Any:
    if isinstance(hint, type) and issubclass(hint, Message):
        return _carried(value, hint)
    item = _message_item(hint)
    if item is not None and isinstance(value, list):
        return [_carried(v, item) for v in value]
    return value


_FIELD_TYPES: dict[str, dict[str, Any]] = {}


def _field_types(zendock_type: type[Message]) -> dict[str, Any]:
    known = _FIELD_TYPES.get(zendock_type.TYPE_NAME)
    if known is None:
        hints = typing.get_type_hints(zendock_type, include_extras=False)
        known = {f.name: hints[f.name] for f in dataclasses.fields(zendock_type)}  # type: ignore[arg-type]
        _FIELD_TYPES[zendock_type.TYPE_NAME] = known
    return known


def _message_item(hint: Any) -> type[Message] | None:
    if typing.get_origin(hint) is list:
        (item,) = typing.get_args(hint)
        if isinstance(item, type) and issubclass(item, Message):
            return item
    return None
