"""Malformed payloads for one message type, generated from its schema; every one is checked to be refused.

Structure-aware mutation, as libprotobuf-mutator does for protobuf messages: start from a valid message of
the type (its wire map, with lists of nested messages filled in so that nested fields can be reached), then
break one thing: drop or add a field, put a value of the wrong kind, NaN or an infinity, an out-of-range
integer (enums included), an array over the size limit, deep nesting; or break the bytes (truncated,
trailing bytes, a length that lies, garbage), or the encoding (JSON as text/plain, another type's payload
and schema). A candidate that the type's own decoder accepts is thrown away, so nothing sent could be taken
for a real message; one that makes the decoder raise anything but a MessageError is sent and flagged
(``decoder_error``), since services only catch MessageError. Pure: no Zenoh here.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import random
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Annotated, Any

import msgpack

from shared.schema import MAX_ARRAY_LEN, Message, MessageError

MSGPACK = "application/msgpack"
#: Kinds that need the type's schema, and kinds that do not (the only ones for a key of unknown type).
TYPED_KINDS = (
    "missing_field",
    "unknown_field",
    "wrong_type",
    "non_finite",
    "out_of_range",
    "huge_array",
    "long_array",
    "nested_garbage",
    "wrong_schema",
    "wrong_encoding",
)
UNTYPED_KINDS = (
    "garbage",
    "empty",
    "truncated",
    "trailing_bytes",
    "length_lie",
    "wrong_top_level",
    "deep_nesting",
)
#: Integers no sized field accepts all of: enum codes, sign and width boundaries.
OUT_OF_RANGE_INTS = (
    -1,
    7,
    256,
    -129,
    65_536,
    1_000_000_000,
    2**31,
    -(2**31) - 1,
    2**32,
    2**63 - 1,
    -(2**63),
    2**64 - 1,
)
NON_FINITE = (math.nan, math.inf, -math.inf)
#: msgpack's first byte 0xc1 is "never used": no decoder accepts it.
NEVER_VALID = b"\xc1"
LONG_ARRAY_LEN = 10_000
DEEP_NESTING = 800  # below msgpack's own depth limit, so the schema has to refuse it


@dataclass(frozen=True)
class Malformed:
    """One payload to send: ``payload`` ``None`` means a request without a payload.

    ``decoder_error`` is set when the type's decoder refused it with something other than a
    :class:`~shared.schema.MessageError` (a bug in the schema: services only catch ``MessageError``).
    """

    kind: str
    payload: bytes | None
    encoding: str
    decoder_error: str | None = None

    @property
    def size(self) -> int:
        return len(self.payload) if self.payload is not None else 0


def encoding_of(type_name: str) -> str:
    return f"{MSGPACK};{type_name}"


def decode_outcome(
    msg_type: type[Message], payload: bytes | None, empty_request: bytes = b"\x80"
) -> str | None:
    """How ``msg_type``'s decoder takes ``payload``: ``None`` accepted, ``""`` refused with a MessageError,
    else the exception that escaped it. A missing payload is read as ``empty_request``."""
    try:
        msg_type.decode(payload if payload is not None else empty_request)
    except MessageError:
        return ""
    except Exception as exc:  # the finding: a decoder must only ever raise MessageError
        return f"{type(exc).__name__}: {exc}"
    return None


def refused(msg_type: type[Message], payload: bytes | None, empty_request: bytes = b"\x80") -> bool:
    """Whether ``msg_type``'s decoder refuses ``payload`` the way services expect (a MessageError)."""
    return decode_outcome(msg_type, payload, empty_request) == ""


# --- a valid starting point ---------------------------------------------------------------------------


def _base_annotation(annotation: Any) -> Any:
    return typing.get_args(annotation)[0] if typing.get_origin(annotation) is Annotated else annotation


def _message_item(annotation: Any) -> type[Message] | None:
    """The item type of a ``list[SomeMessage]`` field, else None."""
    base = _base_annotation(annotation)
    if typing.get_origin(base) is list:
        (item,) = typing.get_args(base)
        if isinstance(item, type) and issubclass(item, Message):
            return item
    return None


def _nested_message(annotation: Any) -> type[Message] | None:
    base = _base_annotation(annotation)
    return base if isinstance(base, type) and issubclass(base, Message) else None


def rich_example(msg_type: type[Message]) -> dict[str, Any]:
    """The default message's wire map, with every list of nested messages holding two of them."""
    wire = msg_type().to_dict()
    hints = typing.get_type_hints(msg_type, include_extras=True)
    for f in dataclasses.fields(msg_type):  # type: ignore[arg-type]
        item = _message_item(hints[f.name])
        nested = _nested_message(hints[f.name])
        if item is not None and not wire[f.name]:
            wire[f.name] = [rich_example(item), rich_example(item)]
        elif nested is not None:
            wire[f.name] = rich_example(nested)
    try:
        msg_type.from_dict(wire)
    except MessageError:
        return msg_type().to_dict()
    return wire


# --- paths into a wire map ------------------------------------------------------------------------------

Path = tuple[str | int, ...]


def _walk(value: Any, path: Path = ()) -> list[tuple[Path, Any]]:
    """Every (path, value) below the root, depth first (the root itself excluded)."""
    found: list[tuple[Path, Any]] = []
    if isinstance(value, dict):
        for key, child in value.items():
            found.append(((*path, key), child))
            found.extend(_walk(child, (*path, key)))
    elif isinstance(value, list):
        for index, child in enumerate(value[:4]):  # a few items are enough to reach nested fields
            found.append(((*path, index), child))
            found.extend(_walk(child, (*path, index)))
    return found


def _parent(root: Any, path: Path) -> Any:
    node = root
    for part in path[:-1]:
        node = node[part]
    return node


def _replace(root: Any, path: Path, value: Any) -> None:
    _parent(root, path)[path[-1]] = value


class PayloadFactory:
    """Makes malformed payloads, reproducibly from ``rng``; ``huge_budget`` caps the over-limit arrays (4 MB each)."""

    def __init__(self, rng: random.Random, types: Mapping[str, type[Message]], huge_budget: int = 4) -> None:
        self.rng = rng
        self.types = dict(types)
        self.huge_left = huge_budget
        self._examples: dict[str, dict[str, Any]] = {}
        self._typed: dict[str, Callable[[type[Message]], Malformed | None]] = {
            "missing_field": self._missing_field,
            "unknown_field": self._unknown_field,
            "wrong_type": self._wrong_type,
            "non_finite": self._non_finite,
            "out_of_range": self._out_of_range,
            "huge_array": self._huge_array,
            "long_array": self._long_array,
            "nested_garbage": self._nested_garbage,
            "wrong_schema": self._wrong_schema,
            "wrong_encoding": self._wrong_encoding,
        }

    # --- public -----------------------------------------------------------------------------------------

    def typed(self, msg_type: type[Message], empty_request: bytes | None = None) -> Malformed:
        """A payload ``msg_type``'s decoder refuses. For requests, ``empty_request`` is what a missing
        payload is read as (``None``: never send a request without a payload)."""
        read_empty_as = empty_request if empty_request is not None else b"\x80"
        kinds = TYPED_KINDS + UNTYPED_KINDS + (("no_payload",) if empty_request is not None else ())
        for _ in range(12):
            kind = self.rng.choice(kinds)
            if kind == "no_payload":
                candidate: Malformed | None = Malformed(kind, None, encoding_of(msg_type.TYPE_NAME))
            elif kind in self._typed:
                candidate = self._typed[kind](msg_type)
            else:
                candidate = self._untyped(kind, self.example(msg_type), msg_type.TYPE_NAME)
            if candidate is None:
                continue
            outcome = decode_outcome(msg_type, candidate.payload, read_empty_as)
            if outcome == "":
                return candidate
            if outcome is not None:
                return dataclasses.replace(candidate, decoder_error=outcome)
        return Malformed("garbage", NEVER_VALID, encoding_of(msg_type.TYPE_NAME))

    def untyped(self) -> Malformed:
        """A payload for a key of unknown type: broken at the byte level, or not a map at all."""
        kind = self.rng.choice(UNTYPED_KINDS)
        candidate = self._untyped(kind, {"data": self.rng.random()}, "")
        return candidate if candidate is not None else Malformed("garbage", NEVER_VALID, MSGPACK)

    def example(self, msg_type: type[Message]) -> dict[str, Any]:
        if msg_type.TYPE_NAME not in self._examples:
            self._examples[msg_type.TYPE_NAME] = rich_example(msg_type)
        return copy.deepcopy(self._examples[msg_type.TYPE_NAME])

    # --- structure ---------------------------------------------------------------------------------------

    def _pack(self, kind: str, wire: Any, msg_type: type[Message]) -> Malformed | None:
        try:
            payload = msgpack.packb(wire, use_bin_type=True)
        except (OverflowError, TypeError, ValueError):
            return None
        return Malformed(kind, payload, encoding_of(msg_type.TYPE_NAME))

    def _pick(self, wire: Any, accept: Callable[[Path, Any], bool]) -> Path | None:
        paths = [path for path, value in _walk(wire) if accept(path, value)]
        return self.rng.choice(paths) if paths else None

    def _missing_field(self, msg_type: type[Message]) -> Malformed | None:
        wire = self.example(msg_type)
        path = self._pick(wire, lambda p, _v: isinstance(p[-1], str))
        if path is None:
            return None
        del _parent(wire, path)[path[-1]]
        return self._pack("missing_field", wire, msg_type)

    def _unknown_field(self, msg_type: type[Message]) -> Malformed | None:
        wire = self.example(msg_type)
        maps: list[Any] = [wire, *(v for _p, v in _walk(wire) if isinstance(v, dict))]
        target = self.rng.choice(maps)
        target[f"fuzz_{self.rng.randrange(1 << 16)}"] = self._leaf()
        return self._pack("unknown_field", wire, msg_type)

    def _wrong_type(self, msg_type: type[Message]) -> Malformed | None:
        wire = self.example(msg_type)
        path = self._pick(wire, lambda _p, _v: True)
        if path is None:
            return None
        current = _parent(wire, path)[path[-1]]
        options = [
            v
            for v in ("text", None, True, [1, "x"], {"x": 1}, b"\x00\x01", 3, 2.5)
            if type(v) is not type(current)
        ]
        _replace(wire, path, self.rng.choice(options))
        return self._pack("wrong_type", wire, msg_type)

    def _non_finite(self, msg_type: type[Message]) -> Malformed | None:
        wire = self.example(msg_type)
        path = self._pick(wire, lambda _p, v: type(v) is float)
        if path is None:
            return None
        _replace(wire, path, self.rng.choice(NON_FINITE))
        return self._pack("non_finite", wire, msg_type)

    def _out_of_range(self, msg_type: type[Message]) -> Malformed | None:
        wire = self.example(msg_type)
        path = self._pick(wire, lambda _p, v: type(v) is int)
        if path is None:
            return None
        _replace(wire, path, self.rng.choice(OUT_OF_RANGE_INTS))
        return self._pack("out_of_range", wire, msg_type)

    def _huge_array(self, msg_type: type[Message]) -> Malformed | None:
        if self.huge_left <= 0:
            return None
        wire = self.example(msg_type)
        path = self._pick(wire, lambda _p, v: isinstance(v, (list, bytes)))
        if path is None:
            return None
        _replace(
            wire, path, bytes(MAX_ARRAY_LEN + 1) if self.rng.random() < 0.5 else [0] * (MAX_ARRAY_LEN + 1)
        )
        self.huge_left -= 1
        return self._pack("huge_array", wire, msg_type)

    def _long_array(self, msg_type: type[Message]) -> Malformed | None:
        """Long but legal length, one bad item at the end: the decoder has to read it all to refuse it."""
        wire = self.example(msg_type)
        path = self._pick(wire, lambda _p, v: isinstance(v, (list, bytes)))
        if path is None:
            return None
        bad = self.rng.choice(["x", None, math.nan, {"x": 1}, 2**63 - 1])
        _replace(wire, path, [1] * (LONG_ARRAY_LEN - 1) + [bad])
        return self._pack("long_array", wire, msg_type)

    def _nested_garbage(self, msg_type: type[Message]) -> Malformed | None:
        wire = self.example(msg_type)
        path = self._pick(wire, lambda _p, _v: True)
        garbage = self.rng.choice(
            [
                _nest(DEEP_NESTING, []),
                _nest(DEEP_NESTING, {}),
                {"header": {"header": {"header": None}}},
                [[{"x": [1, [2, [3]]]}]],
                msgpack.ExtType(5, b"\x00\x01"),
            ]
        )
        if path is None:
            wire = garbage
        else:
            _replace(wire, path, garbage)
        return self._pack("nested_garbage", wire, msg_type)

    def _wrong_schema(self, msg_type: type[Message]) -> Malformed | None:
        others = [t for name, t in self.types.items() if name != msg_type.TYPE_NAME]
        if not others:
            return None
        other = self.rng.choice(others)
        payload = other().encode()
        return Malformed("wrong_schema", payload, encoding_of(other.TYPE_NAME))

    def _wrong_encoding(self, msg_type: type[Message]) -> Malformed | None:
        """The message as JSON text (a plausible mistake), labelled text/plain or application/json."""
        text = json.dumps(msg_type().to_dict(), default=lambda v: v.hex() if isinstance(v, bytes) else str(v))
        return Malformed("wrong_encoding", text.encode(), self.rng.choice(["text/plain", "application/json"]))

    # --- bytes ------------------------------------------------------------------------------------------

    def _untyped(self, kind: str, wire: Any, type_name: str) -> Malformed | None:
        encoding = encoding_of(type_name) if type_name else MSGPACK
        valid = msgpack.packb(wire, use_bin_type=True)
        if kind == "garbage":
            return Malformed(kind, self.rng.randbytes(self.rng.randrange(1, 512)), encoding)
        if kind == "empty":
            return Malformed(kind, b"", encoding)
        if kind == "truncated":
            return Malformed(kind, valid[: self.rng.randrange(1, max(2, len(valid)))], encoding)
        if kind == "trailing_bytes":
            return Malformed(kind, valid + self.rng.randbytes(self.rng.randrange(1, 16)), encoding)
        if kind == "length_lie":  # an array or map header claiming 2**32 - 1 entries, then little else
            return Malformed(
                kind, self.rng.choice([b"\xdd", b"\xdf", b"\xdb"]) + b"\xff\xff\xff\xff" + valid[:8], encoding
            )
        if kind == "wrong_top_level":
            value = self.rng.choice([None, 42, -1.5, "cmd", True, [wire], b"\x00" * 8])
            return Malformed(kind, msgpack.packb(value, use_bin_type=True), encoding)
        if kind == "deep_nesting":
            return Malformed(kind, b"\x91" * 2_000 + b"\xc0", encoding)  # past msgpack's depth limit
        return None

    def _leaf(self) -> Any:
        return self.rng.choice([1, -1.5, "x", None, True, [1, 2], {"k": "v"}])


def _nest(depth: int, inner: Any) -> Any:
    value = inner
    for _ in range(depth):
        value = [value]
    return value
