"""Every message type's wire form as JSON Schema, generated from the message classes themselves.

A zendock payload is one msgpack map; the schema describes that map once decoded (msgpack maps, arrays,
strings, integers, floats and booleans read as their JSON counterparts). What JSON Schema cannot say is
written in each schema's ``description`` and in :data:`WIRE_RULES`: which floats may be NaN, and that a
byte array longer than 64 items travels as msgpack ``bin``. Decoding is strict, as the schemas say: every
field is required and an unknown field is refused.
"""

from __future__ import annotations

import dataclasses
import typing
from typing import Annotated, Any

import numpy as np

from shared.encoding import ANSWERING_ATTACHMENT_SIZE, ATTACHMENT_SIZE, ENCODING_PREFIX, MAX_PAYLOAD_BYTES
from shared.schema import Message, Range, _AllowNonFinite, _ArraySpec

JSON_SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"

#: The rules every payload follows, for someone writing a publisher or a subscriber in another language.
WIRE_RULES: tuple[str, ...] = (
    f"A sample's payload is one msgpack map whose keys are the ROS 2 field names; at most {MAX_PAYLOAD_BYTES} bytes.",
    f"Its Zenoh encoding is `{ENCODING_PREFIX};<ROS type name>`, e.g. `{ENCODING_PREFIX};sensor_msgs/msg/BatteryState`.",
    f"Its attachment is {ATTACHMENT_SIZE} bytes: the publisher's sequence number (u64 little-endian, from 1), then "
    "the publisher's 16-byte session id and 4-byte entity id (little-endian). The session id is Zenoh's id of "
    "the publishing session (`str(session.zid())`, hexadecimal) read as a number and written as 16 bytes "
    "little-endian; the entity id is the publisher's own. Receivers accept a sample without an attachment. "
    f"A command computed on a control tick may add 8 bytes ({ANSWERING_ATTACHMENT_SIZE} in all): the tick's sim "
    "time in nanoseconds (i64 little-endian), so the simulator's lockstep knows which step the command answers; "
    "a command without them counts as computed when it arrives.",
    "Every field is present and no other: a map with a missing or an unknown field is refused (counted, logged once).",
    "Numbers: floats are msgpack float 64 (an integer is accepted where a float is expected); they must be finite "
    "unless the schema says NaN is allowed (then NaN means 'unknown', as ROS 2 uses it). Integers are range-checked.",
    "Numeric arrays (ROS `float64[]`, `uint8[]`, ...) are msgpack arrays; `uint8`/`int8` arrays longer than 64 items "
    "travel as msgpack `bin` (raw bytes), shorter ones as arrays; a receiver accepts either.",
    "Nested messages are nested maps; `builtin_interfaces/Time` is `{sec: int32, nanosec: uint32}`.",
    "Requests are Zenoh queries with the request map as payload; a reply is the response map, or an error reply "
    "(`reply_err`, text) when the request does not decode or the server refuses it.",
)


def _number(bounds: Range | None, nan_allowed: bool) -> dict[str, Any]:
    schema: dict[str, Any] = {"type": "number"}
    if bounds is not None:
        schema.update(minimum=bounds.lo, maximum=bounds.hi)
    if nan_allowed:
        schema["description"] = "NaN and infinities allowed"
    return schema


def _array(spec: _ArraySpec) -> dict[str, Any]:
    kind = spec.dtype.kind
    if kind == "f":
        item: dict[str, Any] = {"type": "number"}
        about = f"{spec.dtype.name} values" + (", NaN allowed" if spec.allow_nonfinite else ", finite")
    else:
        info = np.iinfo(spec.dtype.type)  # type: ignore[type-var]
        item = {"type": "integer", "minimum": int(info.min), "maximum": int(info.max)}
        about = f"{spec.dtype.name} values; more than 64 travel as msgpack bin (raw bytes)"
    return {"type": "array", "items": item, "description": about}


def field_schema(annotation: Any, defs: dict[str, Any]) -> dict[str, Any]:
    """The schema of one field annotation; nested message types are added to ``defs`` once each."""
    base: Any = annotation
    extras: tuple[Any, ...] = ()
    if typing.get_origin(annotation) is Annotated:
        base, *rest = typing.get_args(annotation)
        extras = tuple(rest)
    bounds = next((e for e in extras if isinstance(e, Range)), None)
    array = next((e for e in extras if isinstance(e, _ArraySpec)), None)
    if array is not None:
        return _array(array)
    if base is float:
        return _number(bounds, any(isinstance(e, _AllowNonFinite) for e in extras))
    if base is int:
        schema: dict[str, Any] = {"type": "integer"}
        if bounds is not None:
            schema.update(minimum=int(bounds.lo), maximum=int(bounds.hi))
        return schema
    if base is bool:
        return {"type": "boolean"}
    if base is str:
        return {"type": "string"}
    if isinstance(base, type) and issubclass(base, Message):
        _define(base, defs)
        return {"$ref": f"#/$defs/{_def_name(base)}"}
    if typing.get_origin(base) is list:
        (item,) = typing.get_args(base)
        return {"type": "array", "items": field_schema(item, defs)}
    raise TypeError(f"no schema for the annotation {annotation!r}")


def _def_name(cls: type[Message]) -> str:
    return cls.TYPE_NAME.replace("/", ".")


def _object(cls: type[Message], defs: dict[str, Any]) -> dict[str, Any]:
    hints = typing.get_type_hints(cls, include_extras=True)
    names = [f.name for f in dataclasses.fields(cls)]  # type: ignore[arg-type]
    return {
        "title": cls.TYPE_NAME,
        "type": "object",
        "properties": {name: field_schema(hints[name], defs) for name in names},
        "required": names,
        "additionalProperties": False,
    }


def _define(cls: type[Message], defs: dict[str, Any]) -> None:
    name = _def_name(cls)
    if name not in defs:
        defs[name] = {}  # a placeholder first: a type that nests itself terminates
        defs[name] = _object(cls, defs)


def json_schema(cls: type[Message]) -> dict[str, Any]:
    """The JSON Schema (2020-12) of one message type's decoded payload."""
    defs: dict[str, Any] = {}
    schema = {"$schema": JSON_SCHEMA_DIALECT, "$id": f"zendock:{cls.TYPE_NAME}", **_object(cls, defs)}
    if defs:
        schema["$defs"] = dict(sorted(defs.items()))
    return schema
