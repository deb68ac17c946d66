"""One error type for user-written files (worlds, stacks, parameters), with messages that name the place."""

from __future__ import annotations

from pathlib import Path

from pydantic import ValidationError


class ConfigError(ValueError):
    """A user-written file or value is malformed. The message names the file, the field and the reason."""


def format_validation_error(error: ValidationError, source: str | Path, root: str = "") -> str:
    """Render a pydantic error as ``source: field.path: reason`` lines, one per problem."""
    lines = []
    for item in error.errors():
        parts = [root] if root else []
        parts += [str(p) for p in item["loc"] if p != "__root__"]
        where = ".".join(parts) or "(top level)"
        reason = item["msg"]
        if reason.startswith("Value error, "):
            reason = reason[len("Value error, "):]
        if item["type"] == "extra_forbidden":
            reason = "unknown key"
        lines.append(f"{source}: {where}: {reason}")
    return "\n".join(lines)
