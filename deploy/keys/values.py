"""A message from a YAML snippet, the way ``ros2 topic pub`` builds one.

The YAML is merged over the type's defaults, so ``{linear: {x: 0.2}}`` is a whole Twist; list items
that are messages are merged over their own defaults. Two keywords from ``ros2 topic pub``: a Time
field given as ``now`` and a Header given as ``auto`` (stamp now, empty frame) are filled in when the
message is built, so each publication carries a fresh stamp. The merged map is then validated by the
schema: any error names the field, and nothing is sent.
"""

from __future__ import annotations

import dataclasses
import time
import typing
from collections.abc import Callable
from typing import Annotated, Any, cast

import yaml

from deploy.keys.errors import EXIT_USAGE, KeysError
from deploy.keys.types import known_types
from shared.messages import Header, Time
from shared.schema import Message, MessageError
from shared.suggestions import closest_names

NOW = "now"
AUTO = "auto"


def resolve_type(type_text: str) -> type[Message]:
    """``geometry_msgs/msg/Twist``, ``geometry_msgs/Twist`` or a unique ``Twist`` -> its message class."""
    types = known_types()
    text = type_text.strip()
    if text in types:
        return types[text]
    parts = text.split("/")
    if len(parts) == 2 and f"{parts[0]}/msg/{parts[1]}" in types:
        return types[f"{parts[0]}/msg/{parts[1]}"]
    if len(parts) == 1:
        found = [name for name in types if name.rsplit("/", 1)[-1] == text]
        if len(found) == 1:
            return types[found[0]]
        if len(found) > 1:
            raise KeysError(f"type {text!r} is ambiguous: {', '.join(sorted(found))}", EXIT_USAGE)
    close = closest_names(text, types, n=3, cutoff=0.5)
    hint = f"; did you mean {' or '.join(close)}?" if close else ""
    raise KeysError(f"unknown message type {text!r}{hint}", EXIT_USAGE)


def parse_yaml_values(text: str) -> dict[str, Any]:
    """The user's YAML as a mapping (empty text means all defaults)."""
    try:
        values = yaml.safe_load(text) if text.strip() else {}
    except yaml.YAMLError as exc:
        detail = str(exc).replace("\n", " ")
        raise KeysError(f"values are not valid YAML: {detail}", EXIT_USAGE) from None
    if values is None:
        return {}
    if not isinstance(values, dict):
        raise KeysError(
            f"values must be a YAML mapping such as '{{linear: {{x: 0.2}}}}', got {type(values).__name__}",
            EXIT_USAGE,
        )
    return values


def _field_classes(cls: type[Message]) -> dict[str, Any]:
    """Each field's annotation with ``Annotated`` unwrapped."""
    hints = typing.get_type_hints(cls, include_extras=True)
    plain = {}
    for f in dataclasses.fields(cast(Any, cls)):  # every Message is a dataclass
        hint = hints[f.name]
        plain[f.name] = typing.get_args(hint)[0] if typing.get_origin(hint) is Annotated else hint
    return plain


def _message_class(annotation: Any) -> type[Message] | None:
    return annotation if isinstance(annotation, type) and issubclass(annotation, Message) else None


def _list_item_class(annotation: Any) -> type[Message] | None:
    if typing.get_origin(annotation) is list:
        (item,) = typing.get_args(annotation)
        return _message_class(item)
    return None


def merge_over_defaults(
    cls: type[Message], values: dict[str, Any], now_s: float, path: str = ""
) -> dict[str, Any]:
    """The wire map of ``cls``'s defaults with ``values`` laid over it (see the module doc)."""
    try:
        merged = cls().to_dict()
    except TypeError:  # a type without defaults for every field: the user must give the rest
        merged = {}
    fields = _field_classes(cls)
    for name, value in values.items():
        where = f"{path}.{name}" if path else str(name)
        if name not in fields:
            known = ", ".join(fields)
            raise MessageError(
                f"unknown field for {cls.TYPE_NAME} (fields: {known})", type_name=cls.TYPE_NAME, field=where
            )
        annotation = fields[name]
        nested = _message_class(annotation)
        item_cls = _list_item_class(annotation)
        if nested is Time and value == NOW:
            merged[name] = Time.from_sec(now_s).to_dict()
        elif nested is Header and value == AUTO:
            merged[name] = Header(Time.from_sec(now_s), "").to_dict()
        elif nested is not None and isinstance(value, dict):
            merged[name] = merge_over_defaults(nested, value, now_s, where)
        elif item_cls is not None and isinstance(value, list):
            merged[name] = [
                merge_over_defaults(item_cls, item, now_s, f"{where}[{i}]")
                if isinstance(item, dict)
                else item
                for i, item in enumerate(value)
            ]
        else:
            merged[name] = value
    return merged


def build_message(cls: type[Message], values: dict[str, Any], now_s: float | None = None) -> Message:
    """Merge and validate; :class:`KeysError` (usage) naming the field when the values do not fit."""
    stamp = time.time() if now_s is None else now_s
    try:
        return cls.from_dict(merge_over_defaults(cls, values, stamp))
    except MessageError as exc:
        where = f"field '{exc.field}': " if exc.field else ""
        raise KeysError(f"invalid {cls.TYPE_NAME}: {where}{exc.reason}", EXIT_USAGE) from None


def message_factory(cls: type[Message], values: dict[str, Any]) -> Callable[[float], Message]:
    """Validate now, then build a fresh message (fresh ``now``/``auto`` stamps) per publication."""
    build_message(cls, values)
    return lambda now_s: build_message(cls, values, now_s)
