"""``zendock keys pub KEY [TYPE] 'YAML'``: publish a validated message, as ``ros2 topic pub`` does.

TYPE may be left out when a publisher or subscriber token on the key announces one. The values are
merged over the type's defaults and validated before anything is declared (exit 2 naming the field,
nothing sent). Messages go out through a :class:`~shared.node.Node` publisher, so they carry the
``application/msgpack;<type>`` encoding and a sequence number, and the tool's own ``pub`` token shows in
``list -v`` while it runs. With a count (``--once``, ``--times``) it first waits briefly for a subscriber,
as ``ros2 topic pub`` does, so the first messages are not published into the void.
"""

from __future__ import annotations

import math
import os
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TextIO

import zenoh

from deploy.keys.connection import BusOptions, open_bus, resolve_key
from deploy.keys.decoding import message_tree
from deploy.keys.errors import EXIT_USAGE, KeysError
from deploy.keys.graph import query_graph
from deploy.keys.render import flow_text
from deploy.keys.values import message_factory, parse_yaml_values, resolve_type
from shared.node import Node
from shared.schema import Message

DEFAULT_RATE_HZ = 1.0
DEFAULT_WAIT_MATCHING_S = 2.0
GRAPH_TIMEOUT_S = 2.0


@dataclass(frozen=True)
class PubRequest:
    key: str
    type_name: str | None = None
    values_yaml: str = ""
    rate_hz: float = DEFAULT_RATE_HZ
    times: int | None = None  # None: until Ctrl-C
    wait_matching_s: float = DEFAULT_WAIT_MATCHING_S
    quiet: bool = False

    def check(self) -> None:
        if not (self.rate_hz > 0 and math.isfinite(self.rate_hz)):
            raise KeysError(f"--rate must be a positive number of Hz, got {self.rate_hz:g}", EXIT_USAGE)
        if self.times is not None and self.times < 1:
            raise KeysError(f"--times must be at least 1, got {self.times}", EXIT_USAGE)
        if self.wait_matching_s < 0:
            raise KeysError(f"--wait-matching must not be negative, got {self.wait_matching_s:g}", EXIT_USAGE)


def looks_like_type(text: str) -> bool:
    """Whether a lone argument after KEY is a type name rather than YAML values."""
    stripped = text.strip()
    if not stripped or any(c in stripped for c in "{}[]:, "):
        return False
    if "/" in stripped:
        return True
    try:
        resolve_type(stripped)
    except KeysError:
        return False
    return True


def split_type_and_values(arguments: Sequence[str]) -> tuple[str | None, str]:
    """``[TYPE] [VALUES]`` after KEY: ``(type or None, yaml text)``."""
    if len(arguments) == 0:
        return None, ""
    if len(arguments) == 1:
        return (arguments[0], "") if looks_like_type(arguments[0]) else (None, arguments[0])
    if len(arguments) == 2:
        return arguments[0], arguments[1]
    raise KeysError(
        f"expected KEY [TYPE] [VALUES], got {len(arguments) + 1} arguments (quote the YAML values)",
        EXIT_USAGE,
    )


def _relative_key(namespace: str, key: str) -> str:
    return key[len(namespace) + 1 :] if namespace else key


def _is_matching(status: object) -> bool:
    """zenoh 1.10 returns a ``MatchingStatus`` where its stubs promise a bool: accept both."""
    return bool(getattr(status, "matching", status))


def wait_for_subscriber(session: zenoh.Session, key: str, timeout_s: float, stop: threading.Event) -> bool:
    """True once a subscriber matching ``key`` is routed to this session (or at once if one already is)."""
    matched = threading.Event()

    def on_matching(status: object) -> None:
        if _is_matching(status):
            matched.set()

    probe = session.declare_publisher(key)
    try:
        listener = probe.declare_matching_listener(on_matching)
        try:
            if _is_matching(probe.matching_status):
                return True
            deadline = time.monotonic() + timeout_s
            while not matched.is_set() and not stop.is_set():
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    break
                matched.wait(min(remaining, 0.2))
            return matched.is_set()
        finally:
            listener.undeclare()
    finally:
        probe.undeclare()


def _choose_type(
    requested: type[Message] | None, announced: list[str], key: str, err: TextIO
) -> type[Message]:
    if requested is not None:
        if announced and requested.TYPE_NAME not in announced:
            err.write(
                f"zendock keys pub: warning: {key} is announced as {', '.join(announced)}, "
                f"publishing {requested.TYPE_NAME} anyway\n"
            )
        return requested
    if not announced:
        raise KeysError(
            f"no publisher or subscriber on {key} announces a type; give TYPE after the key", EXIT_USAGE
        )
    if len(announced) > 1:
        raise KeysError(
            f"{key} is announced with several types ({', '.join(announced)}); give TYPE", EXIT_USAGE
        )
    return resolve_type(announced[0])


def run_pub(
    options: BusOptions,
    request: PubRequest,
    out: TextIO,
    err: TextIO | None = None,
    stop: threading.Event | None = None,
) -> int:
    """Validate, then publish ``times`` messages (or until ``stop``/Ctrl-C) at ``rate_hz``."""
    request.check()
    err = err or sys.stderr
    stop = stop or threading.Event()
    key = resolve_key(options.namespace, request.key, allow_wildcards=False)
    values = parse_yaml_values(request.values_yaml)
    requested = resolve_type(request.type_name) if request.type_name else None
    if requested is not None:
        message_factory(requested, values)  # refuse bad values before touching the bus
    with open_bus(options) as session:
        entry = query_graph(session, GRAPH_TIMEOUT_S).entry(key)
        msg_type = _choose_type(requested, entry.topic_types if entry else [], key, err)
        make_message = message_factory(msg_type, values)
        with Node(f"keys_pub_{os.getpid()}", session, options.namespace) as node:
            publisher = node.create_publisher(msg_type, _relative_key(options.namespace, key))
            if request.times is not None and request.wait_matching_s > 0:
                if not wait_for_subscriber(session, key, request.wait_matching_s, stop):
                    err.write(
                        f"zendock keys pub: no subscriber on {key} after {request.wait_matching_s:g} s; "
                        "publishing anyway\n"
                    )
            sent = _publish_loop(request, publisher.publish, make_message, key, out, stop)
    if not request.quiet:
        out.write(f"published {sent} {msg_type.TYPE_NAME} message(s) on {key}\n")
    return 0


def _publish_loop(
    request: PubRequest,
    publish: Callable[[Message], None],
    make_message: Callable[[float], Message],
    key: str,
    out: TextIO,
    stop: threading.Event,
) -> int:
    period_s = 1.0 / request.rate_hz
    next_send = time.monotonic()
    sent = 0
    try:
        while (request.times is None or sent < request.times) and not stop.is_set():
            msg = make_message(time.time())
            publish(msg)
            sent += 1
            if not request.quiet:
                out.write(f"publishing #{sent} on {key}: {flow_text(message_tree(msg))}\n")
                out.flush()
            if request.times is not None and sent >= request.times:
                break
            next_send += period_s
            stop.wait(max(0.0, next_send - time.monotonic()))
    except KeyboardInterrupt:
        pass
    return sent
