"""Strict typed records (msgspec ``Struct``): validating user-written values into them, with plain messages
that name the place, and reading what their fields are.

Parameters, worlds and dock databases are records of this kind. They are checked where they come in
(a file, ``-p``, ``zendock param set``), by :func:`validate`; a record built in code by its constructor
is trusted, as a dataclass is. A field's bounds, description and extra keys live in its
``Annotated[T, msgspec.Meta(...)]``, so one declaration feeds validation, ``zendock param list`` and the
contract pages. msgspec builds a record class in tens of microseconds and imports in a few milliseconds,
which keeps a service's start short (issue 55's 150 ms).

A validator is a ``__post_init__`` that raises ``ValueError``. Its message starts with the field's name
(``"resume_at: must be above ..."``) when one field is at fault, so the message names the field.
"""

from __future__ import annotations

import contextlib
import copy
import functools
import math
import re
import typing
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Literal, TypeVar, get_args, get_origin

import msgspec

from shared.config_errors import ConfigError
from shared.suggestions import did_you_mean

T = TypeVar("T")

_AT = re.compile(r"^(?P<message>.*?)(?: - at `\$(?P<path>[^`]*)`)?$", re.DOTALL)
_UNKNOWN = re.compile(r"^Object contains unknown field `(?P<name>[^`]*)`$")
_MISSING = re.compile(r"^Object missing required field `(?P<name>[^`]*)`$")
_BOUND = re.compile(r"^Expected `(?P<type>[^`]*)` (?P<op>>=|<=|>|<) (?P<bound>\S+)$")
_LENGTH = re.compile(r"^Expected `(?P<type>[^`]*)` of length (?P<op>>=|<=) (?P<bound>\d+)$")
_EXACT = re.compile(r"^Expected `(?P<type>[^`]*)` of length (?P<want>\d+), got (?P<got>\d+)$")
_TYPE = re.compile(r"^Expected `(?P<want>[^`]*)`, got `(?P<got>[^`]*)`$")
_ENUM = re.compile(r"^Invalid enum value (?P<value>.*)$")
_STEP = re.compile(r"\.(?P<field>[^.\[]+)|\[(?P<item>\d+|\.\.\.)\]")
#: How msgspec's own messages (types, bounds, keys) begin, as against a record's ``__post_init__`` checks.
_OWN_MESSAGES = ("Expected ", "Object ", "Invalid ")
_NAMED = re.compile(r"^(?P<name>[A-Za-z_][\w.]*): (?P<reason>.*)$", re.DOTALL)
_BOUND_WORDS = {">=": "at least", ">": "greater than", "<=": "at most", "<": "less than"}
_LENGTH_WORDS = {">=": "at least", "<=": "at most"}


class FieldSpec(msgspec.Struct, frozen=True):
    """One field of a record: its name, its type without ``Annotated``, and what its ``Meta`` says."""

    name: str
    type: Any
    description: str
    extra: dict[str, Any]

    @property
    def group(self) -> type[msgspec.Struct] | None:
        """The record type of this field when it is a nested group of fields, else None."""
        return self.type if _is_struct_type(self.type) else None


def _is_struct_type(kind: Any) -> bool:
    return isinstance(kind, type) and issubclass(kind, msgspec.Struct)


def _strip(annotation: Any) -> tuple[Any, list[msgspec.Meta]]:
    """The type under ``Annotated`` and its ``Meta`` objects."""
    metas: list[msgspec.Meta] = []
    while get_origin(annotation) is typing.Annotated:
        args = get_args(annotation)
        annotation = args[0]
        metas += [m for m in args[1:] if isinstance(m, msgspec.Meta)]
    return annotation, metas


@functools.cache
def fields(record: type[msgspec.Struct]) -> tuple[FieldSpec, ...]:
    """The fields of a record type, in declaration order."""
    specs = []
    for info in msgspec.structs.fields(record):
        kind, metas = _strip(info.type)
        description = next((m.description for m in metas if m.description), "")
        extra: dict[str, Any] = {}
        for meta in metas:
            extra.update(meta.extra or {})
        specs.append(FieldSpec(info.name, kind, description or "", extra))
    return tuple(specs)


def field_names(record: type[msgspec.Struct]) -> list[str]:
    return [spec.name for spec in fields(record)]


def field_spec(record: type[msgspec.Struct], name: str) -> FieldSpec | None:
    return next((spec for spec in fields(record) if spec.name == name), None)


#: At most this many problems are listed for one file; msgspec finds one at a time (see :func:`validate`).
MAX_PROBLEMS = 20


def validate(record: type[T], data: Any, source: str | Path, root: str = "") -> T:
    """``data`` (plain values: YAML, JSON, ``-p``) as a ``record``, or a :class:`ConfigError` naming
    ``source``, the field and the reason, one line per problem. Numbers given as text and ints for floats
    are accepted, as a user would expect; out-of-bounds, unknown and missing fields are not.

    msgspec stops at the first problem. So that a file with several mistakes is not mended one run at a
    time, each blamed key is left out and the rest validated again, while the place is a key of a mapping
    (not a list item, whose removal would renumber the rest) and what follows is not the key's own absence
    nor a check of the record's own (``__post_init__``), which would judge a default in the left-out
    value's place.
    """
    try:
        return msgspec.convert(data, record, strict=False)
    except msgspec.ValidationError as exc:
        lines = [_line(source, root, where, reason) for where, reason in _problems(exc, record, data)]
        raise ConfigError("\n".join(lines)) from None


def _problems(error: msgspec.ValidationError, record: type, data: Any) -> Iterator[tuple[str, str]]:
    """The first problem's place and reason, then those found with the keys already blamed left out (see
    :func:`validate`)."""
    remaining = copy.deepcopy(data)
    left_out: set[str] = set()
    for _ in range(MAX_PROBLEMS):
        where, reason = explain(error, record, remaining)
        if _MISSING.match(_message_of(error)) and where in left_out:
            return  # the key's own absence, not a mistake of the user's
        yield where, reason
        if not _leave_out(remaining, where):
            return
        left_out.add(where)
        try:
            msgspec.convert(remaining, record, strict=False)
            return
        except msgspec.ValidationError as exc:
            error = exc
        if not _message_of(error).startswith(_OWN_MESSAGES):
            return  # a check of the record's own would judge the defaults put in place of what was left out


def _message_of(error: msgspec.ValidationError) -> str:
    match = _AT.match(str(error))
    return match.group("message") if match else str(error)


def _leave_out(data: Any, where: str) -> bool:
    """Remove the key at dotted ``where`` from nested mappings; False where that cannot be done cleanly."""
    *parents, last = where.split(".") if where else [""]
    here = data
    for part in parents:
        if not isinstance(here, dict) or part not in here:
            return False
        here = here[part]
    if not isinstance(here, dict) or last not in here:
        return False
    del here[last]
    return True


def _line(source: str | Path, root: str, where: str, reason: str) -> str:
    """``source: field.path: reason`` (``root``: the place of the validated values in their file)."""
    place = ".".join(part for part in (root, where) if part)
    return f"{source}: {place}: {reason}" if place else f"{source}: {reason}"


@contextlib.contextmanager
def blaming(field: str) -> Iterator[None]:
    """In a ``__post_init__``: a ``ValueError`` raised inside (a file that does not load, a name that does
    not normalise) is raised again with ``field`` first, so that :func:`validate` names the field."""
    try:
        yield
    except ValueError as exc:
        raise ValueError(f"{field}: {exc}") from None


def explain(error: msgspec.ValidationError, record: type, data: Any = None) -> tuple[str, str]:
    """The dotted place (``lidar.noise_m``, ``walls.0``, ``services.planner.restart``) and the reason in
    plain words. msgspec does not say which key of a mapping was at fault: it is found in ``data`` (the values
    that were validated), else written ``[...]``."""
    match = _AT.match(str(error))
    message = match.group("message") if match else str(error)
    parts = _path_parts(match.group("path") if match and match.group("path") else "", record, data)
    for pattern, words in (
        (_UNKNOWN, "unknown key"),
        (_MISSING, "missing (required)"),
    ):
        found = pattern.match(message)
        if found:
            name = found.group("name")
            reason = words
            if pattern is _UNKNOWN:
                reason += did_you_mean(name, _names_at(record, parts))
            return ".".join([*parts, name]), reason
    named = _NAMED.match(message)
    if named and not _BOUND.match(message):
        return ".".join([*parts, named.group("name")]), named.group("reason")
    return ".".join(parts), _plain_reason(message, _type_at(record, parts))


def _path_parts(path: str, record: Any = None, data: Any = None) -> list[str]:
    """``.walls[0].pose`` -> ``["walls", "0", "pose"]``; ``.services[...].restart`` -> ``["services",
    "planner", "restart"]``, the key found in ``data`` as the first whose value ``record`` refuses there."""
    parts: list[str] = []
    value = data
    for step in _STEP.finditer(path):
        part = step.group("field") or step.group("item")
        if part == "...":
            part, value = _refused_key(_type_at(record, parts), value)
        else:
            value = _child(value, part)
        parts.append(part)
    return parts


def _child(value: Any, part: str) -> Any:
    if isinstance(value, dict):
        return value.get(part)
    if isinstance(value, (list, tuple)) and part.isdigit() and int(part) < len(value):
        return value[int(part)]
    return None


def _refused_key(kind: Any, mapping: Any) -> tuple[str, Any]:
    """The first key of ``mapping`` (a ``dict[K, V]`` value) whose value is not a valid ``V``, and that value;
    msgspec stops at the first, as this does."""
    if get_origin(kind) is dict and isinstance(mapping, dict):
        item_type = get_args(kind)[-1]
        for key, item in mapping.items():
            try:
                msgspec.convert(item, item_type, strict=False)
            except msgspec.ValidationError:
                return str(key), item
    return "[...]", None


def _type_at(record: Any, parts: list[str]) -> Any:
    """The declared type at a path inside ``record`` (None where the path leaves what is declared)."""
    kind = record
    for part in parts:
        kind, _metas = _strip(kind)
        kind = _unoptional(kind)
        if _is_struct_type(kind):
            spec = field_spec(kind, part)
            if spec is None:
                return None
            kind = spec.type
        elif get_origin(kind) in (list, tuple, dict):
            args = get_args(kind)
            if not args:
                return None
            kind = args[-1] if get_origin(kind) is dict else args[0]
        else:
            return None
    return _unoptional(_strip(kind)[0])


def _unoptional(kind: Any) -> Any:
    args = get_args(kind)
    if args and type(None) in args and len(args) == 2:
        return next(arg for arg in args if arg is not type(None))
    return kind


def _names_at(record: Any, parts: list[str]) -> list[str]:
    kind = _type_at(record, parts)
    return field_names(kind) if _is_struct_type(kind) else []


def _plain_reason(message: str, kind: Any) -> str:
    bound = _BOUND.match(message)
    if bound:
        return f"must be {_BOUND_WORDS[bound.group('op')]} {bound.group('bound')}"
    length = _LENGTH.match(message)
    if length:
        if length.group("op") == ">=" and length.group("bound") == "1":
            return "must not be empty"
        unit = "characters" if length.group("type") == "str" else "items"
        return f"must have {_LENGTH_WORDS[length.group('op')]} {length.group('bound')} {unit}"
    exact = _EXACT.match(message)
    if exact:
        return f"must have {exact.group('want')} items, got {exact.group('got')}"
    wrong = _TYPE.match(message)
    if wrong:
        return f"expected {_type_words(wrong.group('want'))}, got {_type_words(wrong.group('got'))}"
    if _ENUM.match(message) and get_origin(kind) is Literal:
        choices = ", ".join(repr(choice) for choice in get_args(kind))
        return f"{message[0].lower()}{message[1:]} (choose from {choices})"
    return (
        message[0].lower() + message[1:] if message[:1].isupper() and not message[1:2].isupper() else message
    )


def _type_words(name: str) -> str:
    """msgspec's name of a type in plain words; ``str | null`` is ``text or nothing``."""
    words = {"array": "a list", "object": "a mapping", "str": "text", "null": "nothing"}
    return " or ".join(words.get(part, part) for part in name.split(" | "))


def plain(value: Any) -> Any:
    """A record or value as JSON-ready builtins (records become dicts, tuples lists)."""
    return _lists(msgspec.to_builtins(value))


def _lists(value: Any) -> Any:
    if isinstance(value, (list, tuple)):
        return [_lists(item) for item in value]
    if isinstance(value, dict):
        return {key: _lists(item) for key, item in value.items()}
    return value


def non_finite(record: msgspec.Struct) -> Iterator[str]:
    """The names of ``record``'s float fields (or float items of tuple fields) that are inf or nan."""
    for name in record.__struct_fields__:
        value = getattr(record, name)
        items = value if isinstance(value, tuple) else (value,)
        if any(isinstance(item, float) and not math.isfinite(item) for item in items):
            yield name


__all__ = [
    "FieldSpec",
    "blaming",
    "explain",
    "field_names",
    "field_spec",
    "fields",
    "non_finite",
    "plain",
    "validate",
]
