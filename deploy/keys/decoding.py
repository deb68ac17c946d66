"""A received payload as a printable tree, whatever arrives: decoding never raises.

The sample's encoding names its type (``application/msgpack;geometry_msgs/msg/Twist``). A registered type
is validated and shown in field order; an unknown type or no type is shown as plain msgpack; a payload of
the wrong shape is shown as plain msgpack with a note saying what is wrong; bytes that are not msgpack
are shown as ``<N bytes, not msgpack: 0a0b...>``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, cast

import msgpack
import numpy as np

from deploy.keys.types import known_types
from shared.schema import Message, MessageError

HEX_PREVIEW_BYTES = 32
TEXT_MIMES = ("text/", "application/json", "application/yaml")


@dataclass(frozen=True)
class DecodedSample:
    """One sample as the tools show it.

    ``value`` is the printable tree (dicts in field order, lists, scalars); ``undecodable`` is set when
    the payload is not msgpack at all. ``note`` says why the payload is not what its encoding announced.
    """

    key: str
    payload: bytes
    schema: str = ""
    value: Any = None
    note: str = ""
    message: Message | None = None
    sequence: int | None = None
    undecodable: bool = False
    #: msgpack, but not a valid message of the registered type its encoding announced.
    invalid: bool = False

    @property
    def type_label(self) -> str:
        return self.schema or "no type"


def hex_preview(payload: bytes, limit: int = HEX_PREVIEW_BYTES) -> str:
    text = payload[:limit].hex()
    return text + ("..." if len(payload) > limit else "")


def undecodable_note(payload: bytes) -> str:
    """How bytes that are not msgpack are shown: ``<5 bytes, not msgpack: 0a0b0c0d0e>``."""
    return f"<{len(payload)} bytes, not msgpack: {hex_preview(payload)}>"


def split_encoding(encoding: str) -> tuple[str, str]:
    """``("application/msgpack", "geometry_msgs/msg/Twist")`` from the encoding's text."""
    mime, _, schema = encoding.partition(";")
    return mime, schema


def message_tree(msg: Message) -> dict[str, Any]:
    """A validated message as plain values in field order; numeric arrays become lists."""
    fields = dataclasses.fields(cast(Any, msg))  # every Message is a dataclass (shared.schema.message)
    return {f.name: _plain(getattr(msg, f.name)) for f in fields}


def _plain(value: Any) -> Any:
    if isinstance(value, Message):
        return message_tree(value)
    if isinstance(value, np.ndarray):
        if value.dtype == np.float32:  # shortest repr of each float32, not its float64 widening
            return [float(str(v)) for v in value]
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def decode_payload(
    key: str, payload: bytes, encoding: str = "", sequence: int | None = None
) -> DecodedSample:
    """Decode one payload for display (see the module doc); never raises."""
    mime, schema = split_encoding(encoding)
    if mime.startswith(TEXT_MIMES):
        text = payload.decode("utf-8", errors="replace")
        return DecodedSample(key, payload, schema, value=text, sequence=sequence)
    try:
        plain = msgpack.unpackb(payload, raw=False, strict_map_key=False)
    except Exception:  # msgpack raises several unrelated types for garbage
        return DecodedSample(
            key, payload, schema, note=undecodable_note(payload), sequence=sequence, undecodable=True
        )
    if not schema:
        return DecodedSample(key, payload, schema, value=plain, sequence=sequence)
    cls = known_types().get(schema)
    if cls is None:
        note = f"type {schema} is not known to this zendock; shown as plain msgpack"
        return DecodedSample(key, payload, schema, value=plain, note=note, sequence=sequence)
    try:
        msg = cls.from_dict(plain)
    except MessageError as exc:
        where = f"field '{exc.field}': " if exc.field else ""
        note = f"not a valid {schema}: {where}{exc.reason}; shown as plain msgpack"
        return DecodedSample(key, payload, schema, value=plain, note=note, sequence=sequence, invalid=True)
    return DecodedSample(key, payload, schema, value=message_tree(msg), message=msg, sequence=sequence)
