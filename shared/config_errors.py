"""One error type for user-written files (worlds, stacks, parameters), with messages that name the place."""

from __future__ import annotations

from pathlib import Path
from typing import Any

#: The exit code of a process stopped by a :class:`ConfigError` (a service, a ``zendock`` command), as
#: argparse exits on a bad flag. Restarting cannot fix one, so the launcher never restarts a service for it.
CONFIG_ERROR_EXIT = 2


class ConfigError(ValueError):
    """A user-written file or value is malformed. The message names the file, the field and the reason."""


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
