"""Where the bus is, from the environment: the one reading every zendock process makes of it.

``ZENOH_LISTEN`` is where the router listens; a process connects to ``ZENDOCK_CONNECT``, else
``ZENOH_CONNECT`` (each comma-separated). Each is read from the process environment, else from ``./.env``
(as ``zendock up`` reads the stack's variables: the environment wins). The router (``zendock router``),
every service, whether the launcher started it or a user ran ``python -m services.viz`` by hand, and every
CLI command read them here, so one ``export ZENOH_LISTEN=... ZENOH_CONNECT=...``, or the same two lines in
``./.env``, moves them all. Flags (``--listen``, ``--connect``) win over both. No bus.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

from shared.config_errors import ConfigError
from shared.interpolation import InterpolationError, parse_env_file

#: Read in this order; the first that is set (and not empty) holds.
CONNECT_VARIABLES = ("ZENDOCK_CONNECT", "ZENOH_CONNECT")
LISTEN_VARIABLE = "ZENOH_LISTEN"
#: The variables file read beside the environment, in the working directory (``zendock up``'s default too).
DOTENV = Path(".env")


def bus_environment(dotenv: Path = DOTENV) -> Mapping[str, str]:
    """The process environment with the bus variables ``dotenv`` sets that the environment does not.

    A ``dotenv`` that cannot be read is a :class:`ConfigError` naming its line: it would otherwise send a
    process to another bus than ``zendock up`` uses, in silence."""
    if not dotenv.is_file():
        return os.environ
    try:
        values = parse_env_file(dotenv, os.environ)
    except (InterpolationError, OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{exc}" if isinstance(exc, InterpolationError) else f"{dotenv}: {exc}") from None
    found = {name: values[name] for name in (*CONNECT_VARIABLES, LISTEN_VARIABLE) if name in values}
    return {**found, **os.environ}


def _endpoints(text: str) -> tuple[str, ...]:
    return tuple(part.strip() for part in text.split(",") if part.strip())


def connect_from_env(environ: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """The endpoints a process connects to by the environment, else ``./.env`` (empty: none said)."""
    env = bus_environment() if environ is None else environ
    for name in CONNECT_VARIABLES:
        found = _endpoints(env.get(name, ""))
        if found:
            return found
    return ()


def listen_from_env(environ: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """The endpoints the router listens on by the environment, else ``./.env`` (empty: none said)."""
    env = bus_environment() if environ is None else environ
    return _endpoints(env.get(LISTEN_VARIABLE, ""))
