"""What a view message is: a Foxglove-schema payload with its channel's schema, ready for any sink.

A :class:`ViewMessage` carries bytes already encoded (protobuf for the Foxglove schemas, JSON for
zendock's own small records), so the live WebSocket server and the MCAP recorder write exactly the same
thing: one conversion, two sinks.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

from foxglove.messages import Timestamp

from shared.messages import Time


@dataclass(frozen=True, slots=True)
class ViewSchema:
    """A channel's schema as MCAP and the Foxglove WebSocket protocol describe it."""

    name: str
    encoding: str  # protobuf | jsonschema
    data: bytes
    message_encoding: str  # protobuf | json


@dataclass(frozen=True, slots=True)
class ViewMessage:
    """One encoded Foxglove-schema message on a view topic (e.g. ``/scan``).

    ``stamp_ns`` is the message's own time (its header stamp) when it has one: the live view uses it as
    the log time, so every channel shares the robot's clock.
    """

    topic: str
    schema: ViewSchema
    data: bytes
    stamp_ns: int | None = None


_PROTOBUF_SCHEMAS: dict[Any, ViewSchema] = {}


def protobuf_schema(message_class: Any) -> ViewSchema:
    """The schema of a :mod:`foxglove.messages` class (cached: each class builds its descriptor once)."""
    schema = _PROTOBUF_SCHEMAS.get(message_class)
    if schema is None:
        raw = message_class.get_schema()
        schema = ViewSchema(raw.name, raw.encoding, bytes(raw.data), "protobuf")
        _PROTOBUF_SCHEMAS[message_class] = schema
    return schema


def protobuf_view(topic: str, message: Any, stamp_ns: int | None = None) -> ViewMessage:
    """A :mod:`foxglove.messages` object encoded for ``topic``."""
    return ViewMessage(topic, protobuf_schema(type(message)), message.encode(), stamp_ns)


def json_schema(title: str, properties: dict[str, Any]) -> ViewSchema:
    """A JSON-encoded channel described by a JSON schema of flat ``properties``."""
    document = {"title": title, "type": "object", "properties": properties}
    return ViewSchema(title, "jsonschema", json.dumps(document, sort_keys=True).encode(), "json")


def json_view(
    topic: str, schema: ViewSchema, record: dict[str, Any], stamp_ns: int | None = None
) -> ViewMessage:
    """A JSON record; NaN and infinities (unmeasured values) become ``null``, which JSON can carry."""
    clean = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in record.items()}
    return ViewMessage(topic, schema, json.dumps(clean, separators=(",", ":")).encode(), stamp_ns)


def stamp_ns(stamp: Time) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def timestamp(stamp: Time) -> Timestamp:
    """A ROS time as Foxglove's; negative times (never sent by zendock) clamp to zero."""
    if stamp.sec < 0:
        return Timestamp(0, 0)
    return Timestamp(stamp.sec, stamp.nanosec)


def timestamp_from_ns(ns: int) -> Timestamp:
    ns = max(0, ns)
    return Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)
