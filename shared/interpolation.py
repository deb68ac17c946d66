"""Compose-style variable interpolation and ``.env`` files.

Supported forms (as in the Compose specification's "Interpolation" section): ``$VAR``, ``${VAR}``,
``${VAR:-default}`` (unset or empty), ``${VAR-default}`` (unset), ``${VAR:?message}`` / ``${VAR?message}``
(required), ``${VAR:+replacement}`` / ``${VAR+replacement}``, and ``$$`` for a literal ``$``. Defaults may
themselves hold variables: ``${A:-${B:-x}}``.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_OPERATORS = (":-", ":?", ":+", "-", "?", "+")


class InterpolationError(ValueError):
    """A ``${...}`` expression is malformed or a required variable is missing."""


def interpolate(text: str, env: Mapping[str, str]) -> str:
    """Substitute every variable in ``text``; unset variables without a default become empty text."""
    out: list[str] = []
    i = 0
    while i < len(text):
        char = text[i]
        if char != "$":
            out.append(char)
            i += 1
            continue
        following = text[i + 1 : i + 2]
        if following == "$":
            out.append("$")
            i += 2
        elif following == "{":
            end = _closing_brace(text, i + 2)
            out.append(_expand(text[i + 2 : end], env))
            i = end + 1
        else:
            match = _NAME_RE.match(text, i + 1)
            if match is None:
                out.append("$")
                i += 1
            else:
                out.append(env.get(match.group(0), ""))
                i = match.end()
    return "".join(out)


def _closing_brace(text: str, start: int) -> int:
    depth = 1
    i = start
    while i < len(text):
        if text.startswith("${", i):
            depth += 1
            i += 2
            continue
        if text[i] == "}":
            depth -= 1
            if depth == 0:
                return i
        i += 1
    raise InterpolationError(f"unclosed '${{' in {text!r}")


def _expand(expression: str, env: Mapping[str, str]) -> str:
    match = _NAME_RE.match(expression)
    if match is None:
        raise InterpolationError(f"invalid variable name in '${{{expression}}}'")
    name = match.group(0)
    rest = expression[match.end() :]
    if not rest:
        return env.get(name, "")
    operator = next((op for op in _OPERATORS if rest.startswith(op)), None)
    if operator is None:
        raise InterpolationError(f"invalid interpolation '${{{expression}}}'")
    argument = rest[len(operator) :]
    value = env.get(name)
    is_set = value is not None
    is_set_non_empty = bool(value)
    present = is_set_non_empty if operator.startswith(":") else is_set
    kind = operator[-1]
    if kind == "-":
        return value if present and value is not None else interpolate(argument, env)
    if kind == "+":
        return interpolate(argument, env) if present else ""
    # kind == "?": required
    if present and value is not None:
        return value
    message = interpolate(argument, env) or "is not set"
    raise InterpolationError(f"required variable {name} is missing: {message}")


def interpolate_tree(node: object, env: Mapping[str, str], path: tuple[str, ...] = ()) -> object:
    """Interpolate every string value of a parsed YAML document (keys are left alone, as in Compose).

    Errors carry the dotted path of the offending value as their first argument's prefix.
    """
    if isinstance(node, str):
        try:
            return interpolate(node, env)
        except InterpolationError as exc:
            raise InterpolationError(f"{'.'.join(path) or '(top level)'}: {exc}") from None
    if isinstance(node, dict):
        return {key: interpolate_tree(value, env, (*path, str(key))) for key, value in node.items()}
    if isinstance(node, list):
        return [interpolate_tree(value, env, (*path, str(index))) for index, value in enumerate(node)]
    return node


def parse_env_file(path: Path, env: Mapping[str, str] | None = None) -> dict[str, str]:
    """Read ``KEY=VALUE`` lines (``export`` prefix, ``#`` comments, quotes) as Compose reads ``.env``.

    Double-quoted and unquoted values are interpolated against ``env`` and the keys read so far;
    single-quoted values are literal.
    """
    values: dict[str, str] = {}
    for number, raw_line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        line = raw_line.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith("export "):
            line = line[len("export ") :].lstrip()
        key, sep, value = line.partition("=")
        key = key.strip()
        if not sep or not _NAME_RE.fullmatch(key):
            raise InterpolationError(f"{path}:{number}: expected KEY=VALUE, got {raw_line!r}")
        value = value.strip()
        scope = {**(env or {}), **values}
        try:
            if len(value) >= 2 and value[0] == value[-1] == "'":
                values[key] = value[1:-1]
            elif len(value) >= 2 and value[0] == value[-1] == '"':
                inner = value[1:-1].replace("\\n", "\n").replace('\\"', '"')
                values[key] = interpolate(inner, scope)
            else:
                values[key] = interpolate(value.split(" #", 1)[0].rstrip(), scope)
        except InterpolationError as exc:
            raise InterpolationError(f"{path}:{number}: {exc}") from None
    return values
