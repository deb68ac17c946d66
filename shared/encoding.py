"""How a zendock sample is labelled on the wire: its encoding and its attachment.

Every sample's encoding is ``application/msgpack;<ROS type name>``, and its attachment carries the
publisher's sequence number (u64 little-endian) then the publisher's 20-byte global id. A command may add
the sim time of the control tick it answers (i64 nanoseconds, little-endian), so the simulator's lockstep
knows which step a late command belongs to. Recorders, replay and bridges read these without a node, so
they live apart from the endpoints that write them.
"""

from __future__ import annotations

import math
import struct

import zenoh

ENCODING_PREFIX = "application/msgpack"
#: Payloads larger than this are refused before decoding (a 2000 x 2000 map is 4 MB).
MAX_PAYLOAD_BYTES = 8 * 1024 * 1024
_SEQ = struct.Struct("<Q")
_EID = struct.Struct("<I")
_ANSWERS = struct.Struct("<q")
#: Every zendock sample's attachment: its sequence number, then its publisher's global id.
ATTACHMENT_SIZE = _SEQ.size + 16 + _EID.size
#: ... and a command's, with the sim time of the control tick it answers after them.
ANSWERING_ATTACHMENT_SIZE = ATTACHMENT_SIZE + _ANSWERS.size


def encoding_for(type_name: str) -> zenoh.Encoding:
    """``application/msgpack`` with the ROS type name as schema."""
    return zenoh.Encoding(f"{ENCODING_PREFIX};{type_name}")


def schema_of(encoding: zenoh.Encoding | None) -> tuple[str, str]:
    """``(mime, schema)`` of a sample's encoding, e.g. ``("application/msgpack", "sensor_msgs/msg/Range")``."""
    text = str(encoding) if encoding is not None else ""
    mime, _, schema = text.partition(";")
    return mime, schema


def publisher_gid(entity: zenoh.EntityGlobalId) -> bytes:
    """20 bytes naming a publisher across the whole system: its session's id, then its entity id."""
    return int(str(entity.zid), 16).to_bytes(16, "little") + _EID.pack(entity.eid)


def sequence_attachment(sequence: int, gid: bytes, answers_s: float | None = None) -> bytes:
    """The attachment of a zendock sample: the sequence number (u64 little-endian), then the publisher's id,
    then (for a command computed on a control tick) the tick's sim time in nanoseconds (i64 little-endian).

    One attachment carries them all (as rmw_zenoh's does), rather than a sequence attachment plus Zenoh's
    source info: a second extension on every sample adds to every round trip.
    """
    raw = _SEQ.pack(sequence) + gid
    if answers_s is None or not math.isfinite(answers_s):  # no tick yet (a stop before the first one)
        return raw
    return raw + _ANSWERS.pack(round(answers_s * 1e9))


def sequence_number(attachment: zenoh.ZBytes | bytes | None) -> int | None:
    """The per-publisher sequence number a zendock publisher attaches to every sample."""
    raw = _attachment_bytes(attachment)
    return _SEQ.unpack_from(raw)[0] if raw is not None and len(raw) in _SIZES else None


def publisher_id(attachment: zenoh.ZBytes | bytes | None) -> bytes | None:
    """The publisher's id from a zendock sample's attachment (``None`` when the sample has none)."""
    raw = _attachment_bytes(attachment)
    return raw[_SEQ.size : ATTACHMENT_SIZE] if raw is not None and len(raw) in _SIZES[1:] else None


def answered_tick_s(attachment: zenoh.ZBytes | bytes | None) -> float | None:
    """The sim time (s) of the control tick a command answers, from its attachment (``None``: not said)."""
    raw = _attachment_bytes(attachment)
    if raw is None or len(raw) != ANSWERING_ATTACHMENT_SIZE:
        return None
    return float(_ANSWERS.unpack_from(raw, ATTACHMENT_SIZE)[0]) / 1e9


_SIZES = (_SEQ.size, ATTACHMENT_SIZE, ANSWERING_ATTACHMENT_SIZE)


def _attachment_bytes(attachment: zenoh.ZBytes | bytes | None) -> bytes | None:
    return attachment if attachment is None or isinstance(attachment, bytes) else attachment.to_bytes()
