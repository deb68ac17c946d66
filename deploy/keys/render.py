"""How decoded messages read: YAML-like blocks as ``ros2 topic echo`` prints them, CSV rows, hex.

Numeric arrays print on one line (``[0.5, 0.5, ... +358 more (360 items)]``) so a scan stays readable;
floats print at full precision with YAML's ``.nan``/``.inf``; strings are quoted only when YAML needs it.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
from dataclasses import dataclass
from typing import Any, TextIO

import yaml

from deploy.keys.decoding import DecodedSample, hex_preview

DEFAULT_ARRAY_LIMIT = 16
SEPARATOR = "---"
_INDEX_RE = re.compile(r"\[(-?\d+)\]")


class FieldNotFound(LookupError):
    """``--field`` names something the message does not have; the message says which part."""


@dataclass(frozen=True)
class EchoFormat:
    """How ``echo`` prints each message."""

    field: str = ""
    csv: bool = False
    raw: bool = False
    array_limit: int = DEFAULT_ARRAY_LIMIT  # 0: print whole arrays
    show_key: bool = False
    show_sequence: bool = False
    #: A valid message without ``field`` is an error (one key, one type); off for wildcard keys.
    strict_field: bool = True


# --- scalars and lists ----------------------------------------------------------------------------


def format_scalar(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return repr(value)
    if isinstance(value, (bytes, bytearray)):
        return f"<{len(value)} bytes: {hex_preview(bytes(value))}>"
    if isinstance(value, str):
        return format_string(value)
    return format_string(repr(value))  # msgpack extension types and the like


def format_string(text: str) -> str:
    """A string as a YAML scalar: plain when it reads back as the same string, quoted otherwise."""
    if not text.isprintable():  # newlines, tabs, control characters: double quotes with escapes
        return json.dumps(text, ensure_ascii=False)
    try:
        if text and text.strip() == text and not text.startswith(("'", '"')) and yaml.safe_load(text) == text:
            return text
    except yaml.YAMLError:
        pass
    return "'" + text.replace("'", "''") + "'"


def _is_scalar(value: Any) -> bool:
    return not isinstance(value, (dict, list, tuple))


def format_flow_list(items: list[Any] | tuple[Any, ...], array_limit: int) -> str:
    """``[1.0, 2.0, 3.0]``, truncated after ``array_limit`` items (0 keeps them all)."""
    shown = items if array_limit <= 0 or len(items) <= array_limit else items[:array_limit]
    text = ", ".join(format_scalar(v) for v in shown)
    if len(shown) < len(items):
        text += f", ... +{len(items) - len(shown)} more ({len(items)} items)"
    return f"[{text}]"


# --- YAML-like blocks -----------------------------------------------------------------------------


def yaml_lines(value: Any, array_limit: int = DEFAULT_ARRAY_LIMIT) -> list[str]:
    """The lines of ``value`` as a YAML-like block, nested maps indented by two spaces."""
    if isinstance(value, dict):
        return _map_lines(value, array_limit)
    if isinstance(value, (list, tuple)):
        if all(_is_scalar(v) for v in value):
            return [format_flow_list(value, array_limit)]
        return _block_list_lines(value, array_limit)
    return [format_scalar(value)]


def _map_lines(mapping: dict[Any, Any], array_limit: int) -> list[str]:
    if not mapping:
        return ["{}"]
    lines: list[str] = []
    for name, value in mapping.items():
        label = format_scalar(name)
        if isinstance(value, dict) and value:
            lines.append(f"{label}:")
            lines += ["  " + line for line in _map_lines(value, array_limit)]
        elif isinstance(value, (list, tuple)) and value and not all(_is_scalar(v) for v in value):
            lines.append(f"{label}:")
            lines += _block_list_lines(value, array_limit)
        else:
            lines.append(f"{label}: {yaml_lines(value, array_limit)[0]}")
    return lines


def _block_list_lines(items: list[Any] | tuple[Any, ...], array_limit: int) -> list[str]:
    lines: list[str] = []
    for item in items:
        item_lines = yaml_lines(item, array_limit)
        lines.append("- " + item_lines[0])
        lines += ["  " + line for line in item_lines[1:]]
    return lines


# --- fields and CSV -------------------------------------------------------------------------------


def select_field(value: Any, path: str) -> Any:
    """The part of ``value`` at a dotted path; list items by index (``poses.0.pose`` or ``poses[0].pose``)."""
    parts = [p for p in _INDEX_RE.sub(r".\1", path).split(".") if p]
    if not parts:
        raise FieldNotFound(f"--field {path!r} names no field")
    current = value
    for depth, part in enumerate(parts):
        where = ".".join(parts[:depth]) or "the message"
        if isinstance(current, dict):
            if part not in current:
                known = ", ".join(str(k) for k in current) or "none"
                raise FieldNotFound(f"no field '{part}' in {where} (fields: {known})")
            current = current[part]
        elif isinstance(current, (list, tuple)):
            try:
                current = current[int(part)]
            except ValueError:
                raise FieldNotFound(f"{where} is a list: expected an index, got '{part}'") from None
            except IndexError:
                raise FieldNotFound(f"index {part} out of range: {where} has {len(current)} items") from None
        else:
            raise FieldNotFound(f"{where} is a {type(current).__name__}, it has no field '{part}'")
    return current


def flatten(value: Any) -> list[Any]:
    """Leaves of a tree in order (maps by field order, lists by index)."""
    if isinstance(value, dict):
        return [leaf for v in value.values() for leaf in flatten(v)]
    if isinstance(value, (list, tuple)):
        return [leaf for v in value for leaf in flatten(v)]
    return [value]


def csv_row(value: Any) -> str:
    """One CSV line holding every leaf of ``value``."""
    cells = []
    for leaf in flatten(value):
        if isinstance(leaf, str):
            cells.append(leaf)
        elif isinstance(leaf, float):
            cells.append(repr(leaf))
        else:
            cells.append(format_scalar(leaf))
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="").writerow(cells)
    return buffer.getvalue()


# --- one echoed sample ----------------------------------------------------------------------------


def sample_lines(sample: DecodedSample, fmt: EchoFormat) -> list[str]:
    """What ``echo`` prints for one sample (without the ``---`` separator).

    Raises :class:`FieldNotFound` only when a validly decoded message lacks ``fmt.field`` and
    ``fmt.strict_field`` is set: the field can then never be found on the key, which is the user's
    mistake. Otherwise bad payloads and missing fields become notes.
    """
    lines: list[str] = []
    if fmt.show_key or fmt.show_sequence:
        header = f"# {sample.key} [{sample.type_label}]"
        if fmt.show_sequence and sample.sequence is not None:
            header += f" seq {sample.sequence}"
        lines.append(header)
    if fmt.raw:
        return lines + [sample.payload.hex()]
    if sample.undecodable:
        return lines + [("# " if fmt.csv else "") + sample.note]
    if sample.note:
        lines.append(f"# {sample.note}")
    value = sample.value
    if fmt.field:
        try:
            value = select_field(value, fmt.field)
        except FieldNotFound as exc:
            if sample.message is not None and fmt.strict_field:
                raise FieldNotFound(f"{sample.schema} on {sample.key}: {exc}") from None
            return lines + [f"# --field {fmt.field}: {exc}"]
    if fmt.csv:
        return lines + [csv_row(value)]
    return lines + yaml_lines(value, fmt.array_limit)


def write_sample(out: TextIO, sample: DecodedSample, fmt: EchoFormat) -> None:
    lines = sample_lines(sample, fmt)
    if not fmt.csv:
        lines.append(SEPARATOR)
    out.write("\n".join(lines) + "\n")
    out.flush()


def flow_text(value: Any, array_limit: int = DEFAULT_ARRAY_LIMIT) -> str:
    """``value`` on one line in YAML flow style: ``{linear: {x: 0.2, y: 0.0}, angular: {...}}``."""
    if isinstance(value, dict):
        return (
            "{"
            + ", ".join(f"{format_scalar(k)}: {flow_text(v, array_limit)}" for k, v in value.items())
            + "}"
        )
    if isinstance(value, (list, tuple)):
        if all(_is_scalar(v) for v in value):
            return format_flow_list(value, array_limit)
        return "[" + ", ".join(flow_text(v, array_limit) for v in value) + "]"
    return format_scalar(value)
