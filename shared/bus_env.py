"""Where the bus is, from the environment: the one reading every zendock process makes of it.

``ZENOH_LISTEN`` is where the router listens; a process connects to ``ZENDOCK_CONNECT``, else
``ZENOH_CONNECT`` (each comma-separated). The router (``zendock router``), every service, whether the
launcher started it or a user ran ``python -m services.viz`` by hand, and every CLI command read them
here, so one ``export ZENOH_LISTEN=... ZENOH_CONNECT=...`` moves them all. Flags (``--listen``,
``--connect``) win over both. Pure: no bus.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

#: Read in this order; the first that is set (and not empty) holds.
CONNECT_VARIABLES = ("ZENDOCK_CONNECT", "ZENOH_CONNECT")
LISTEN_VARIABLE = "ZENOH_LISTEN"


def _endpoints(text: str) -> tuple[str, ...]:
    return tuple(part.strip() for part in text.split(",") if part.strip())


def connect_from_env(environ: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """The endpoints a process connects to by the environment (empty: none said)."""
    env = os.environ if environ is None else environ
    for name in CONNECT_VARIABLES:
        found = _endpoints(env.get(name, ""))
        if found:
            return found
    return ()


def listen_from_env(environ: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """The endpoints the router listens on by the environment (empty: none said)."""
    env = os.environ if environ is None else environ
    return _endpoints(env.get(LISTEN_VARIABLE, ""))
