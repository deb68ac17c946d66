"""Typed message schemas: dataclasses that mirror ROS 2 messages, encoded as msgpack maps.

A message class is a dataclass decorated with :func:`message`, which records its ROS type name; one
validator per field is compiled when the class is first encoded or decoded (:func:`compile_all` does
it at once). Decoding checks every field (type, range, finiteness, array shape)
and raises :class:`MessageError` naming the key, the type, the field path and the reason; encoding
runs the same checks so an invalid message is refused at the sender.

Field annotations understood:

- ``float`` (finite), :data:`FloatAny` (NaN and infinities allowed), ``int`` and the sized integer
  aliases (:data:`UInt8`, :data:`Int32`, ...), ``bool``, ``str``;
- another message class, or ``list[MessageClass]``;
- numeric arrays :data:`Float64Array`, :data:`Float32Array`, :data:`FloatAnyArray`, :data:`Int8Array`,
  :data:`UInt8Array`: numpy arrays in Python, lists on the wire;
- ``list[str]``.

``Annotated[int, Range(lo, hi)]`` and ``Annotated[float, Range(lo, hi)]`` bound a value.
"""

from __future__ import annotations

import dataclasses
import math
import struct
import threading
import typing
from collections.abc import Callable
from typing import Annotated, Any, ClassVar, TypeVar, dataclass_transform

import msgspec
import numpy as np

MAX_ARRAY_LEN = 4_000_000  # a map of 2000 x 2000 cells; anything larger is refused


class MessageError(ValueError):
    """A payload is not a valid message of the expected type."""

    def __init__(self, reason: str, *, type_name: str = "", field: str = "", key: str = "") -> None:
        self.reason = reason
        self.type_name = type_name
        self.field = field
        self.key = key
        super().__init__(self._text())

    def _text(self) -> str:
        where = [p for p in (self.key, self.type_name) if p]
        prefix = ": ".join(where)
        field = f"field '{self.field}': " if self.field else ""
        return f"{prefix}: {field}{self.reason}" if prefix else f"{field}{self.reason}"

    def at(self, *, key: str | None = None, type_name: str | None = None) -> MessageError:
        """Fill in where the error happened (the innermost type and field are kept)."""
        if key is not None and not self.key:
            self.key = key
        if type_name is not None and not self.type_name:
            self.type_name = type_name
        self.args = (self._text(),)
        return self


class _Slow(Exception):
    """Internal: the generated fast path met something unusual; the general path takes over."""


class _FieldError(Exception):
    """Internal: carries a reason and a field path (built on the way up) to the message level."""

    def __init__(self, path: str, reason: str) -> None:
        self.path = path
        self.reason = reason

    def under(self, parent: str) -> _FieldError:
        if not self.path:
            self.path = parent
        elif self.path.startswith("["):
            self.path = parent + self.path
        else:
            self.path = f"{parent}.{self.path}"
        return self


class Range(msgspec.Struct, frozen=True):
    """Inclusive bounds for a numeric field."""

    lo: float
    hi: float


class _AllowNonFinite:
    pass


class _ArraySpec:
    def __init__(self, dtype: type, allow_nonfinite: bool = False) -> None:
        self.dtype = np.dtype(dtype)
        self.allow_nonfinite = allow_nonfinite


FloatAny = Annotated[float, _AllowNonFinite()]
UInt8 = Annotated[int, Range(0, 255)]
Int8 = Annotated[int, Range(-128, 127)]
Int16 = Annotated[int, Range(-(2**15), 2**15 - 1)]
UInt16 = Annotated[int, Range(0, 65535)]
Int32 = Annotated[int, Range(-(2**31), 2**31 - 1)]
UInt32 = Annotated[int, Range(0, 2**32 - 1)]
Int64 = Annotated[int, Range(-(2**63), 2**63 - 1)]
UInt64 = Annotated[int, Range(0, 2**64 - 1)]
Float64Array = Annotated[np.ndarray, _ArraySpec(np.float64)]
Float32Array = Annotated[np.ndarray, _ArraySpec(np.float32)]
FloatAnyArray = Annotated[np.ndarray, _ArraySpec(np.float32, allow_nonfinite=True)]
Int8Array = Annotated[np.ndarray, _ArraySpec(np.int8)]
UInt8Array = Annotated[np.ndarray, _ArraySpec(np.uint8)]

Validator = Callable[[Any], Any]
#: Validates a Python value and returns its wire form in one pass (the sender's check).
Encoder = Callable[[Any], Any]


class Message:
    """Base of every message class (added by :func:`message`)."""

    TYPE_NAME: ClassVar[str] = ""
    _FIELDS: ClassVar[tuple[tuple[str, Validator, Encoder], ...]] = ()
    #: The generated ``(decode, encode)`` of a message made only of floats (``None`` for the others); see below.
    _FIXED: ClassVar[tuple[Callable[..., Any], Callable[..., bytes]] | None] = None

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        """Reached only while another thread turns this deferred class into its dataclass (between the
        stand-ins' removal and the dataclass's own ``__init__``, see :func:`_make_dataclass`): wait for
        that, then make the message as the dataclass does. Without it, the first two messages of a class
        made at once on two threads could find no ``__init__`` but ``object``'s."""
        cls = type(self)
        _make_dataclass(cls)
        init = cls.__init__
        if init is Message.__init__:
            raise TypeError(f"{cls.__qualname__} is not a message dataclass")
        init(self, *args, **kwargs)

    def to_dict(self) -> dict[str, Any]:
        """The msgpack-ready map, validated (raises :class:`MessageError`)."""
        try:
            return self._fast_encode(self)
        except _FAST_PATH_MISSES:
            pass  # something unusual: the general path decides, and names the field if it is wrong
        try:
            return _encode_message(self)
        except _FieldError as exc:
            raise MessageError(exc.reason, type_name=self.TYPE_NAME, field=exc.path) from None

    @classmethod
    def from_dict(cls: type[M], data: Any) -> M:
        try:
            decoded: M = cls._fast_decode(data)
            return decoded
        except _FAST_PATH_MISSES:
            pass
        try:
            return _decode_message(cls, data)
        except _FieldError as exc:
            raise MessageError(exc.reason, type_name=cls.TYPE_NAME, field=exc.path) from None

    @staticmethod
    def _fast_encode(msg: Any) -> dict[str, Any]:
        raise _Slow

    @staticmethod
    def _fast_decode(data: Any) -> Any:
        raise _Slow

    def encode(self) -> bytes:
        """Validated msgpack bytes (all-float messages replace this with their generated codec)."""
        return _PACK(self.to_dict())

    @classmethod
    def decode(cls: type[M], payload: bytes) -> M:
        """A validated message from msgpack bytes (all-float messages replace this with their generated codec)."""
        return cls.from_dict(unpack(payload, cls.TYPE_NAME))


M = TypeVar("M", bound=Message)
_REGISTRY: dict[str, type[Message]] = {}
_FAST_PATH_MISSES = (_Slow, _FieldError, KeyError, TypeError, AttributeError)


#: The msgpack codec for maps, lists and scalars: msgspec's, which writes the same bytes as msgpack's
#: ``packb(use_bin_type=True)`` (the smallest form of each int, str, bin, array and map; floats as float64)
#: more cheaply (measurement 58). What a payload must hold is checked field by field
#: afterwards (missing and unknown keys included), so the decoder takes any msgpack value.
_PACK = msgspec.msgpack.Encoder().encode
_UNPACK = msgspec.msgpack.Decoder().decode


def unpack(payload: bytes, type_name: str = "") -> Any:
    """msgpack bytes -> Python objects, with a :class:`MessageError` for garbage."""
    try:
        return _UNPACK(payload)
    except Exception as exc:  # garbage, truncation, trailing bytes, unhashable map keys
        detail = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
        raise MessageError(f"payload is not valid msgpack ({detail})", type_name=type_name) from None


class _FieldsOnceMade:
    """``Message.__dataclass_fields__``: reached only while another thread turns a deferred class into its
    dataclass (between the stand-ins' removal and the dataclass's own fields, see :func:`_make_dataclass`),
    or for a class that is no dataclass. It waits for the conversion and answers the dataclass's fields,
    so :func:`dataclasses.fields`, ``is_dataclass`` and ``asdict`` never catch a class half made; a class
    that is no dataclass has none (``AttributeError``, as ``getattr`` with a default expects)."""

    def __get__(self, instance: Any, owner: type | None = None) -> Any:
        cls = owner if instance is None else type(instance)
        if cls is not None and cls is not Message:
            _make_dataclass(cls)
            fields = cls.__dict__.get("__dataclass_fields__")
            if fields is not None and not isinstance(fields, (_FieldsOnceMade, _FieldsOnFirstRead)):
                return fields
        raise AttributeError("__dataclass_fields__")


Message.__dataclass_fields__ = _FieldsOnceMade()  # type: ignore[attr-defined]


def message_type(type_name: str) -> type[Message]:
    """The message class registered under a ROS type name (``KeyError`` if unknown)."""
    return _REGISTRY[type_name]


def registered_types() -> dict[str, type[Message]]:
    return dict(_REGISTRY)


@dataclass_transform()
def message(type_name: str) -> Callable[[type[M]], type[M]]:
    """Class decorator: make a dataclass message registered under ``type_name``."""

    def wrap(cls: type[M]) -> type[M]:
        if not issubclass(cls, Message):
            raise TypeError(f"{cls.__name__} must subclass shared.schema.Message")
        if "__init__" in cls.__dict__:
            cls = dataclasses.dataclass(cls)
        else:
            _GENERATED_INIT.add(cls)
            _defer_dataclass(cls)
        cls.TYPE_NAME = type_name
        for attribute in ("_FIELDS", "_FIXED"):
            setattr(cls, attribute, _CompiledOnFirstRead(cls, attribute))
        if type_name in _REGISTRY and _REGISTRY[type_name].__qualname__ != cls.__qualname__:
            raise ValueError(f"message type {type_name} registered twice")
        _REGISTRY[type_name] = cls
        return cls

    return wrap


#: The dataclass methods a deferred message class gets on first use (see :func:`_defer_dataclass`).
_DATACLASS_METHODS = ("__init__", "__repr__", "__eq__")
_DEFERRED: set[type] = set()
_DEFERRED_LOCK = threading.RLock()


def _defer_dataclass(cls: type[Message]) -> None:
    """Make ``cls`` a dataclass on first use instead of now.

    ``dataclasses.dataclass`` writes and compiles ``__init__``, ``__repr__`` and ``__eq__`` for each class,
    and a service defines far more message classes (every interface its contracts name) than it makes
    (measurement 97). Until then the class carries stand-ins: the three
    methods, and ``__dataclass_fields__`` (which :func:`dataclasses.fields`, ``is_dataclass`` and
    ``asdict`` read). Any of them turns the class into the dataclass it would have been, then answers.
    """
    for name in _DATACLASS_METHODS:
        setattr(cls, name, _stand_in_method(cls, name))
    cls.__dataclass_fields__ = _FieldsOnFirstRead(cls)  # type: ignore[attr-defined]
    _DEFERRED.add(cls)


def _stand_in_method(cls: type[Message], name: str) -> Callable[..., Any]:
    def stand_in(self: Any, *args: Any, **kwargs: Any) -> Any:
        _make_dataclass(cls)
        return getattr(cls, name)(self, *args, **kwargs)

    stand_in.__name__ = stand_in.__qualname__ = name
    return stand_in


class _FieldsOnFirstRead:
    """``__dataclass_fields__`` of a deferred message class: reading it makes the class a dataclass."""

    def __init__(self, cls: type[Message]) -> None:
        self._cls = cls

    def __get__(self, instance: Any, owner: type | None = None) -> Any:
        _make_dataclass(self._cls)
        return self._cls.__dict__["__dataclass_fields__"]


def _make_dataclass(cls: type[Message]) -> None:
    """Turn a deferred class into its dataclass, once (a base class first, when it is deferred too)."""
    with _DEFERRED_LOCK:
        if cls not in _DEFERRED:
            return
        _DEFERRED.discard(cls)  # once: a class whose fields are wrong says so at its first use, not each
        for name in (*_DATACLASS_METHODS, "__dataclass_fields__"):
            delattr(cls, name)
        dataclasses.dataclass(cls)


class _CompiledOnFirstRead:
    """Stands in for a message class's compiled codec until something first reads it.

    A service imports a few hundred message classes (every interface its contracts name) and sends or
    reads a dozen of them. Compiling a class (type hints, one validator per field, generated fast paths)
    costs about as much as defining it, so it waits for the first encode or decode of that class: the
    general path reads ``_FIELDS``, which lands here, and the compiled attributes replace this stand-in
    on the class. Compiling twice from two threads at once gives the same result, so no lock is needed.
    """

    def __init__(self, cls: type[Message], attribute: str) -> None:
        self._cls = cls
        self._attribute = attribute

    def __get__(self, instance: Any, owner: type | None = None) -> Any:
        _compile_message(self._cls)
        return self._cls.__dict__[self._attribute]


def _compile_message(cls: type[Message]) -> None:
    """Give ``cls`` its field validators, fast paths and, for all-float messages, the fixed codec (its fields
    read while another thread makes it a dataclass wait for that: :class:`_FieldsOnceMade`)."""
    hints = typing.get_type_hints(cls, include_extras=True)
    fields = tuple(
        (f.name, *_compile(hints[f.name], f.name))
        for f in dataclasses.fields(cls)  # type: ignore[arg-type]
    )
    cls._FIELDS = fields
    _generate_fast_paths(cls, hints)
    fixed = _generate_fixed_codec(cls)
    if fixed is not None:
        cls.decode = classmethod(fixed[0])  # type: ignore[assignment,method-assign]
        cls.encode = fixed[1]  # type: ignore[method-assign,assignment]
    cls._FIXED = fixed


def compile_all() -> None:
    """Compile every registered message class now (tests and tools that want annotation errors at once)."""
    for cls in list(_REGISTRY.values()):
        _ = cls._FIELDS


# --- compilation of per-field validators and encoders -------------------------------------------
#
# Validators take a value and return it checked; on failure they raise _FieldError with a path relative
# to the value, and each enclosing message or list prepends its own part while the error travels up.
# The success path therefore builds no strings.


def _compile(annotation: Any, name: str) -> tuple[Validator, Encoder]:
    base: Any = annotation
    extras: tuple[Any, ...] = ()
    if typing.get_origin(annotation) is Annotated:
        base, *extras_list = typing.get_args(annotation)
        extras = tuple(extras_list)
    bounds: Range | None = next((e for e in extras if isinstance(e, Range)), None)
    array: _ArraySpec | None = next((e for e in extras if isinstance(e, _ArraySpec)), None)
    if array is not None:
        validate_array = _array_validator(array)
        return validate_array, lambda value: _array_to_wire(validate_array(value))
    if base is float:
        check = _float_validator(any(isinstance(e, _AllowNonFinite) for e in extras), bounds)
        return check, check
    if base is bool:
        return _bool_validator, _bool_validator
    if base is int:
        check = _int_validator(bounds)
        return check, check
    if base is str:
        return _str_validator, _str_validator
    if isinstance(base, type) and issubclass(base, Message):
        return _nested_validator(base), _nested_encoder(base)
    if typing.get_origin(base) is list:
        (item,) = typing.get_args(base)
        if item is str:
            return _str_list_validator, _str_list_validator
        if isinstance(item, type) and issubclass(item, Message):
            return _message_list_validator(item), _message_list_encoder(item)
    raise TypeError(f"field {name!r}: unsupported annotation {annotation!r}")


def _float_validator(allow_nonfinite: bool, bounds: Range | None) -> Validator:
    def check(value: Any) -> float:
        if type(value) is float:
            v = value
        elif isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool):
            v = float(value)
        else:
            raise _FieldError("", f"expected a number, got {type(value).__name__}")
        if not allow_nonfinite and not math.isfinite(v):
            raise _FieldError("", f"must be finite, got {v}")
        if bounds is not None and math.isfinite(v) and not bounds.lo <= v <= bounds.hi:
            raise _FieldError("", f"must be within [{bounds.lo}, {bounds.hi}], got {v}")
        return v

    return check


def _int_validator(bounds: Range | None) -> Validator:
    def check(value: Any) -> int:
        if type(value) is not int and (isinstance(value, bool) or not isinstance(value, (int, np.integer))):
            raise _FieldError("", f"expected an integer, got {type(value).__name__}")
        v = int(value)
        if bounds is not None and not bounds.lo <= v <= bounds.hi:
            raise _FieldError("", f"must be within [{int(bounds.lo)}, {int(bounds.hi)}], got {v}")
        return v

    return check


def _bool_validator(value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise _FieldError("", f"expected true or false, got {type(value).__name__}")
    return bool(value)


def _str_validator(value: Any) -> str:
    if not isinstance(value, str):
        raise _FieldError("", f"expected a string, got {type(value).__name__}")
    return value


def _str_list_validator(value: Any) -> list[str]:
    if not isinstance(value, (list, tuple)):
        raise _FieldError("", f"expected a list of strings, got {type(value).__name__}")
    for i, v in enumerate(value):
        if not isinstance(v, str):
            raise _FieldError(f"[{i}]", f"expected a string, got {type(v).__name__}")
    return list(value)


def _array_validator(spec: _ArraySpec) -> Validator:
    is_float = spec.dtype.kind == "f"

    def check(value: Any) -> np.ndarray:
        if isinstance(value, np.ndarray):
            raw = value
        elif isinstance(value, (list, tuple)):
            if len(value) > MAX_ARRAY_LEN:
                raise _FieldError("", f"array of {len(value)} items exceeds the limit of {MAX_ARRAY_LEN}")
            if not value:
                return np.zeros(0, dtype=spec.dtype)
            # One C-level conversion, then a check of the resulting kind: no Python loop per item.
            try:
                raw = np.asarray(value)
            except (OverflowError, ValueError, TypeError) as exc:
                raise _FieldError("", f"array items must be numbers ({exc})") from None
            if raw.size and raw.dtype.kind not in ("fi" if is_float else "i"):
                if raw.dtype.kind == "f":
                    raise _FieldError("", "array items must be integers, found a fraction")
                bad = next((v for v in value if type(v) not in (int, float)), value[0])
                raise _FieldError("", f"array items must be numbers, found {type(bad).__name__}")
        elif isinstance(value, (bytes, bytearray)) and spec.dtype.itemsize == 1:
            raw = np.frombuffer(bytes(value), dtype=spec.dtype)
        else:
            raise _FieldError("", f"expected a list of numbers, got {type(value).__name__}")
        if raw.ndim != 1:
            raise _FieldError("", f"expected a flat array, got shape {raw.shape}")
        if raw.size > MAX_ARRAY_LEN:
            raise _FieldError("", f"array of {raw.size} items exceeds the limit of {MAX_ARRAY_LEN}")
        if is_float:
            if raw.dtype.kind not in "fiu":
                raise _FieldError("", f"expected numbers, got dtype {raw.dtype}")
            if not spec.allow_nonfinite and raw.size and not np.isfinite(raw).all():
                raise _FieldError("", "array items must be finite")
            return raw.astype(spec.dtype, copy=False)
        if raw.dtype.kind not in "iu":
            raise _FieldError("", f"expected integers, got dtype {raw.dtype}")
        info = np.iinfo(spec.dtype.type)  # type: ignore[type-var]
        if raw.size and (raw.min() < info.min or raw.max() > info.max):
            raise _FieldError("", f"array items must be within [{info.min}, {info.max}]")
        return raw.astype(spec.dtype, copy=False)

    return check


def _array_to_wire(value: np.ndarray) -> Any:
    if value.dtype.itemsize == 1 and value.dtype.kind in "iu" and value.size > 64:
        return value.tobytes()
    return value.tolist()


def _nested_validator(cls: type[Message]) -> Validator:
    def check(value: Any) -> Message:
        return _decode_message(cls, value)

    return check


def _nested_encoder(cls: type[Message]) -> Encoder:
    def encode(value: Any) -> dict[str, Any]:
        if isinstance(value, cls):
            return _encode_message(value)
        if isinstance(value, dict):  # a plain map is accepted if it is a valid message
            return _encode_message(_decode_message(cls, value))
        raise _FieldError("", f"expected {cls.TYPE_NAME}, got {type(value).__name__}")

    return encode


def _message_list_validator(cls: type[Message]) -> Validator:
    def check(value: Any) -> list[Message]:
        if not isinstance(value, (list, tuple)):
            raise _FieldError("", f"expected a list of {cls.TYPE_NAME}, got {type(value).__name__}")
        if len(value) > MAX_ARRAY_LEN:
            raise _FieldError("", f"list of {len(value)} items exceeds the limit of {MAX_ARRAY_LEN}")
        out = []
        for i, v in enumerate(value):
            try:
                out.append(_decode_message(cls, v))
            except _FieldError as exc:
                raise exc.under(f"[{i}]") from None
        return out

    return check


def _message_list_encoder(cls: type[Message]) -> Encoder:
    encode_item = _nested_encoder(cls)

    def encode(value: Any) -> list[dict[str, Any]]:
        if not isinstance(value, (list, tuple)):
            raise _FieldError("", f"expected a list of {cls.TYPE_NAME}, got {type(value).__name__}")
        out = []
        for i, v in enumerate(value):
            try:
                out.append(encode_item(v))
            except _FieldError as exc:
                raise exc.under(f"[{i}]") from None
        return out

    return encode


def _decode_message(cls: type[M], data: Any) -> M:
    if isinstance(data, cls):
        _encode_message(data)  # validates
        return data
    if not isinstance(data, dict):
        raise _FieldError("", f"expected a map for {cls.TYPE_NAME}, got {type(data).__name__}")
    values = {}
    for name, validate, _ in cls._FIELDS:
        try:
            values[name] = validate(data[name])
        except KeyError:
            raise _FieldError(name, "missing") from None
        except _FieldError as exc:
            raise exc.under(name) from None
    if len(data) != len(cls._FIELDS):
        unknown = sorted(str(k) for k in data if k not in values)
        raise _FieldError(unknown[0], f"unknown field for {cls.TYPE_NAME}")
    return cls(**values)


def _encode_message(msg: Message) -> dict[str, Any]:
    out = {}
    for name, _, encode in msg._FIELDS:
        try:
            out[name] = encode(getattr(msg, name))
        except _FieldError as exc:
            raise exc.under(name) from None
    return out


# --- generated fast paths -------------------------------------------------------------------------
#
# For each message class, straight-line code that decodes and encodes the common case (every float a
# finite float, every nested message of its own class) with no per-field function calls. Anything else
# raises _Slow, and the general path above runs instead: it accepts what is valid and names the field
# of what is not, so both paths agree on every input.


def _is_plain_finite_float(annotation: Any) -> bool:
    if annotation is float:
        return True
    if typing.get_origin(annotation) is Annotated:
        base, *extras = typing.get_args(annotation)
        return base is float and not extras
    return False


def _generate_fast_paths(cls: type[Message], hints: dict[str, Any]) -> None:
    env: dict[str, Any] = {"_Slow": _Slow, "cls": cls}
    decode_lines = [
        "def fast_decode(d):",
        f"    if type(d) is not dict or len(d) != {len(cls._FIELDS)}:",
        "        raise _Slow",
    ]
    encode_lines = ["def fast_encode(m):"]
    names = []
    for i, (name, validate, encode) in enumerate(cls._FIELDS):
        annotation = hints[name]
        var = f"v{i}"
        names.append(var)
        decode_lines.append(f"    {var} = d[{name!r}]")
        encode_lines.append(f"    {var} = m.{name}")
        if _is_plain_finite_float(annotation):
            check = f"    if type({var}) is not float or {var} - {var} != 0.0:\n        raise _Slow"
            decode_lines.append(check)
            encode_lines.append(check)
        elif annotation in (str, bool):
            check = f"    if type({var}) is not {annotation.__name__}:\n        raise _Slow"
            decode_lines.append(check)
            encode_lines.append(check)
        elif isinstance(annotation, type) and issubclass(annotation, Message):
            env[f"N{i}"] = annotation
            decode_lines.append(f"    {var} = N{i}._fast_decode({var})")
            encode_lines.append(f"    if type({var}) is not N{i}:\n        raise _Slow")
            encode_lines.append(f"    {var} = N{i}._fast_encode({var})")
        else:
            env[f"V{i}"], env[f"E{i}"] = validate, encode
            decode_lines.append(f"    {var} = V{i}({var})")
            encode_lines.append(f"    {var} = E{i}({var})")
    decode_lines.append(f"    return cls({', '.join(names)})")
    encode_lines.append(
        "    return {" + ", ".join(f"{n!r}: v{i}" for i, (n, _, _) in enumerate(cls._FIELDS)) + "}"
    )
    exec("\n".join(decode_lines), env)  # noqa: S102 - code built from the class's own field names
    exec("\n".join(encode_lines), env)  # noqa: S102
    cls._fast_decode = staticmethod(env["fast_decode"])  # type: ignore[method-assign]
    cls._fast_encode = staticmethod(env["fast_encode"])  # type: ignore[method-assign]


# --- generated bytes codec for all-float messages ----------------------------------------------------
#
# A message whose leaves are all plain finite floats (Vector3, Point, Quaternion, Pose, Twist, ...) has
# one canonical msgpack form: the same map headers and keys at the same offsets, each value a float64
# (0xcb + 8 bytes, big-endian). Round trips of such messages (cmd_vel at the controller rate) are
# dominated by interpreter work, not bytes: building and walking nested dicts, and calling msgpack
# through them. On a busy machine that work runs with cold caches and costs several times its warm
# figure, so it is worth skipping: decode checks the payload's non-float bytes against the canonical
# skeleton in one big-integer comparison and reads all floats with one precompiled ``struct``; encode
# writes them with the same ``struct``. The generated functions replace the class's ``decode`` and
# ``encode`` (one call, no dispatch). Both check finiteness and exact types and hand anything else
# (another encoder's layout, an int in a float field, a NaN, a subclass) to the general path, which
# keeps the last word on what is valid and how an error is named; the bytes are those of msgpack.


def _plain_init(cls: type[Message]) -> bool:
    """Whether ``cls.__init__`` only stores its arguments: generated by dataclass, no post-init hook."""
    params = getattr(cls, "__dataclass_params__", None)
    return (
        cls in _GENERATED_INIT
        and params is not None
        and not params.frozen
        and not hasattr(cls, "__post_init__")
    )


#: Message classes whose ``__init__`` is the one dataclass generated (the class did not define its own).
_GENERATED_INIT: set[type] = set()


def _generate_fixed_codec(cls: type[Message]) -> tuple[Callable[[Any], Any], Callable[[Any], bytes]] | None:
    """``(decode, encode)`` for an all-float message, or ``None`` when the message has other leaves."""
    env: dict[str, Any] = {
        "from_bytes": int.from_bytes,
        "NEW": object.__new__,
        "GENERAL_DECODE": Message.decode.__func__,  # type: ignore[attr-defined]
        "GENERAL_ENCODE": Message.encode,
    }
    class_names: dict[type[Message], str] = {}
    runs: list[bytes] = []  # the constant bytes before each float (and after the last one)
    leaves: list[str] = []  # attribute paths of the floats, in wire order
    checks: list[str] = []  # encode: every nested message is exactly its declared class

    construct: list[str] = []  # decode: statements that build the message, innermost first

    def walk(c: type[Message], path: str, pending: bytes) -> tuple[str, bytes]:
        """Returns the variable that will hold ``c`` and the constant bytes not yet followed by a float."""
        if len(c._FIELDS) > 15:
            raise _Slow  # only fixmap headers: every ROS all-float message has a handful of fields
        name = class_names.setdefault(c, f"C{len(class_names)}")
        env[name] = c
        hints = typing.get_type_hints(c, include_extras=True)
        pending += bytes([0x80 | len(c._FIELDS)])
        values = []
        for field, _, _ in c._FIELDS:
            pending += _PACK(field)
            annotation = hints[field]
            sub_path = f"{path}.{field}"
            if isinstance(annotation, type) and issubclass(annotation, Message):
                checks.append(
                    f"type(m{sub_path}) is not {class_names.setdefault(annotation, f'C{len(class_names)}')}"
                )
                value, pending = walk(annotation, sub_path, pending)
            elif _is_plain_finite_float(annotation):
                runs.append(pending + b"\xcb")
                pending = b""
                value = f"f{len(leaves)}"
                leaves.append(f"m{sub_path}")
            else:
                raise _Slow  # an int, a string, an array...: not a fixed layout
            values.append(value)
        var = f"o{len(construct)}"
        if _plain_init(c):  # what the dataclass __init__ would do, without the call
            sets = "; ".join(f"{var}.{f} = {v}" for (f, _, _), v in zip(c._FIELDS, values))
            construct.append(f"{var} = NEW({name}); {sets}")
        else:
            construct.append(f"{var} = {name}({', '.join(values)})")
        return var, pending

    try:
        result, tail = walk(cls, "", b"")
    except _Slow:
        return None
    if not leaves:
        return None
    runs.append(tail)
    # Decode: padding over the constant bytes; encode: the constant bytes passed as arguments.
    read = struct.Struct(">" + "".join(f"{len(run)}xd" for run in runs[:-1]) + f"{len(runs[-1])}x")
    write = struct.Struct(">" + "".join(f"{len(run)}sd" for run in runs[:-1]) + f"{len(runs[-1])}s")
    skeleton = write.pack(*(v for run in runs[:-1] for v in (run, 0.0)), runs[-1])
    mask = b"".join(b"\xff" * len(run) + b"\x00" * 8 for run in runs[:-1]) + b"\xff" * len(runs[-1])
    env.update(
        SIZE=read.size,
        UNPACK=read.unpack,
        PACK=write.pack,
        MASK=int.from_bytes(mask, "big"),
        SKELETON=int.from_bytes(skeleton, "big"),
    )
    env.update({f"R{i}": run for i, run in enumerate(runs)})
    floats = [f"f{i}" for i in range(len(leaves))]
    not_finite = " or ".join(f"{f} - {f} != 0.0" for f in floats)  # true for NaN and both infinities
    decode = [
        "def fixed_decode(cls, p):",
        "    if cls is not C0 or type(p) is not bytes or len(p) != SIZE or from_bytes(p, 'big') & MASK != SKELETON:",
        "        return GENERAL_DECODE(cls, p)",
        f"    {', '.join(floats)}, = UNPACK(p)",
        f"    if {not_finite}:",
        "        return GENERAL_DECODE(cls, p)  # which names the field",
        *(f"    {line}" for line in construct),
        f"    return {result}",
    ]
    checks.insert(0, "type(m) is not C0")
    encode = [
        "def fixed_encode(m):",
        f"    if {' or '.join(checks)}:",
        "        return GENERAL_ENCODE(m)",
        *(f"    {f} = {leaf}" for f, leaf in zip(floats, leaves)),
        f"    if {' or '.join(f'type({f}) is not float' for f in floats)} or {not_finite}:",
        "        return GENERAL_ENCODE(m)  # accepts an int or a numpy float, names the field of a NaN",
        f"    return PACK({', '.join(f'R{i}, {f}' for i, f in enumerate(floats))}, R{len(floats)})",
    ]
    exec("\n".join(decode), env)  # noqa: S102 - code built from the class's own field names
    exec("\n".join(encode), env)  # noqa: S102
    return env["fixed_decode"], env["fixed_encode"]
