"""Where the ``keys`` verbs connect and how a key typed by a user becomes a Zenoh key.

Endpoints come from ``--connect`` (repeatable), else ``ZENDOCK_CONNECT``, else ``ZENOH_CONNECT`` (both
comma-separated), else the default router. The session is a client that gives up after a bounded connect
timeout, so a missing router is one clear line instead of a hang.

Keys: a key is relative to ``--namespace``. A leading ``/`` (what ROS users type: ``/cmd_vel``) means the
same as without it, "from the namespace root", so ``/cmd_vel`` and ``cmd_vel`` in namespace ``robot1``
are both ``robot1/cmd_vel``. With no namespace a key is the Zenoh key as written.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import zenoh

from deploy.keys.errors import EXIT_USAGE, KeysError
from deploy.options import DEFAULT_CONNECT_TIMEOUT_S
from shared.bus_env import connect_from_env
from shared.names import normalise_namespace, topic_key
from shared.session import DEFAULT_ROUTER_ENDPOINT, SessionSpec, open_session

ENV_NAMESPACE = "ZENDOCK_NAMESPACE"


@dataclass(frozen=True)
class BusOptions:
    """What every verb needs to reach the bus: endpoints, namespace, how long to try."""

    connect: tuple[str, ...] = (DEFAULT_ROUTER_ENDPOINT,)
    namespace: str = ""
    connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S


def resolve_endpoints(
    flags: Sequence[str] | None, environ: Mapping[str, str] | None = None
) -> tuple[str, ...]:
    """``--connect`` flags win, then ``ZENDOCK_CONNECT``, then ``ZENOH_CONNECT``, then the default router."""
    if flags:
        return tuple(flags)
    return connect_from_env(environ) or (DEFAULT_ROUTER_ENDPOINT,)


def bus_options(
    connect: Sequence[str] | None,
    namespace: str | None,
    connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S,
    environ: Mapping[str, str] | None = None,
) -> BusOptions:
    """Validated options from flags and environment (a bad namespace is a usage error)."""
    env = os.environ if environ is None else environ
    raw_namespace = env.get(ENV_NAMESPACE, "") if namespace is None else namespace
    try:
        ns = normalise_namespace(raw_namespace)
    except ValueError as exc:
        raise KeysError(f"--namespace: {exc}", EXIT_USAGE) from None
    if not connect_timeout_s > 0:
        raise KeysError(f"--connect-timeout must be positive, got {connect_timeout_s:g}", EXIT_USAGE)
    return BusOptions(resolve_endpoints(connect, env), ns, connect_timeout_s)


def resolve_key(namespace: str, key: str, *, allow_wildcards: bool = True) -> str:
    """The Zenoh key for ``key`` typed by a user (see the module doc for the leading-slash rule)."""
    try:
        resolved = topic_key(namespace, key)
        zenoh.KeyExpr(resolved)
    except (ValueError, zenoh.ZError) as exc:
        raise KeysError(f"{key!r} is not a valid key: {exc}", EXIT_USAGE) from None
    if not allow_wildcards and has_wildcards(resolved):
        raise KeysError(f"{key!r}: wildcards are not allowed here, give one key", EXIT_USAGE)
    return resolved


def has_wildcards(key: str) -> bool:
    return any(chunk in ("*", "**") or "$*" in chunk for chunk in key.split("/"))


def session_spec(options: BusOptions) -> SessionSpec:
    """A client that fails after ``connect_timeout_s`` instead of retrying for ever."""
    return SessionSpec(
        mode="client",
        connect=options.connect,
        overrides=(
            ("connect/timeout_ms", json.dumps(int(options.connect_timeout_s * 1000))),
            ("connect/exit_on_failure", "true"),
        ),
    )


@contextmanager
def open_bus(options: BusOptions) -> Iterator[zenoh.Session]:
    """A session on the router, closed on exit; :class:`KeysError` when the router cannot be reached."""
    try:
        session = open_session(session_spec(options))
    except zenoh.ZError as exc:
        where = ", ".join(options.connect)
        detail = str(exc).split(" at /")[0]  # drop the Rust source location zenoh appends
        raise KeysError(
            f"cannot reach a Zenoh router at {where} within {options.connect_timeout_s:g} s ({detail}); "
            "is the stack up? (zendock router / --connect ENDPOINT)"
        ) from None
    with session:
        yield session
