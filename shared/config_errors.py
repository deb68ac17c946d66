"""One error type for user-written files (worlds, stacks, parameters), with messages that name the place."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pydantic is heavy (measurement 61); the router and other lean processes never load it
    from pydantic import ValidationError

#: The exit code of a process stopped by a :class:`ConfigError` (a service, a ``zendock`` command), as
#: argparse exits on a bad flag. Restarting cannot fix one, so the launcher never restarts a service for it.
CONFIG_ERROR_EXIT = 2


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
            reason = reason[len("Value error, ") :]
        if item["type"] == "extra_forbidden":
            reason = "unknown key"
        lines.append(f"{source}: {where}: {reason}")
    return "\n".join(lines)


def read_yaml_file(path: str | Path, what: str) -> Any:
    """Parse a user-written YAML file; a missing file or bad YAML is a :class:`ConfigError` naming it.

    ``what`` says what the file is for the message ("world file", "dock database", "map file").
    """
    import yaml  # noqa: PLC0415 - only the loaders need it

    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML: {exc}") from None
