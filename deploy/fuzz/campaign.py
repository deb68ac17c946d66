"""A fuzzing run: find the stack's keys, send each its share of malformed payloads, count everything.

Bounded three ways: a message count, a time limit and (optionally) a rate; requests in flight are capped
too. It only ever talks to a loopback endpoint, as a Zenoh client that neither listens nor scouts, so it
can only reach the stack on this machine. Topics get puts (reliable, blocking under congestion, so a
message counted as sent really left); request endpoints get queries whose replies are counted: an error
reply is the expected answer to a malformed request, silence means the server never answered.
"""

from __future__ import annotations

import ipaddress
import json
import random
import threading
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import zenoh

from deploy.fuzz.payloads import Malformed, PayloadFactory
from deploy.fuzz.targets import REQUEST, TOPIC, Target, graph_targets, known_targets, merge_targets
from deploy.keys.types import known_types
from shared.names import GRAPH_PREFIX, parse_token_key
from shared.schema import Message
from shared.session import SessionSpec, open_session

LOOPBACK_NAMES = ("localhost",)
LOCAL_PROTOCOLS = ("unixsock-stream", "unixpipe")


@dataclass(frozen=True)
class FuzzOptions:
    connect: tuple[str, ...]
    namespace: str = ""
    messages: int = 5000
    seed: int = 0
    #: Messages per second over all keys; 0: as fast as the bus takes them.
    rate_hz: float = 0.0
    time_limit_s: float = 300.0
    query_timeout_s: float = 1.0
    max_in_flight: int = 64
    #: How many over-the-limit arrays (4 MB each) a run may send.
    huge_budget: int = 4
    discovery_timeout_s: float = 2.0
    connect_timeout_s: float = 3.0
    #: A Zenoh json5 file applied first (credentials of a secured router).
    zenoh_config: str | None = None

    def __post_init__(self) -> None:
        if self.messages < 0:
            raise ValueError(f"--messages must be >= 0, got {self.messages}")
        if self.rate_hz < 0:
            raise ValueError(f"--rate must be >= 0, got {self.rate_hz:g}")
        if not self.time_limit_s > 0:
            raise ValueError(f"--time-limit must be positive, got {self.time_limit_s:g}")
        check_loopback(self.connect)


@dataclass
class KeyReport:
    """What one key received: counts by payload kind, and for requests what came back."""

    key: str
    kind: str
    type_name: str | None
    announced: bool
    sent: int = 0
    bytes: int = 0
    kinds: Counter[str] = field(default_factory=Counter)
    replies_ok: int = 0
    replies_err: int = 0
    no_reply: int = 0
    #: Payloads whose decoder failed with something other than a MessageError: exception -> count.
    decoder_errors: Counter[str] = field(default_factory=Counter)

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "kind": self.kind,
            "type": self.type_name,
            "announced": self.announced,
            "sent": self.sent,
            "bytes": self.bytes,
            "kinds": dict(sorted(self.kinds.items())),
        }
        if self.kind == REQUEST:
            out["replies"] = {"ok": self.replies_ok, "error": self.replies_err, "none": self.no_reply}
        if self.decoder_errors:
            out["decoder_errors"] = dict(self.decoder_errors)
        return out


@dataclass
class FuzzReport:
    connect: tuple[str, ...]
    namespace: str
    seed: int
    requested: int
    keys: dict[str, KeyReport] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)
    elapsed_s: float = 0.0
    stopped_by: str = "count"

    @property
    def sent(self) -> int:
        return sum(k.sent for k in self.keys.values())

    @property
    def announced(self) -> int:
        return sum(1 for k in self.keys.values() if k.announced)

    def as_dict(self) -> dict[str, Any]:
        kinds: Counter[str] = Counter()
        for report in self.keys.values():
            kinds.update(report.kinds)
        requests = [k for k in self.keys.values() if k.kind == REQUEST]
        return {
            "connect": list(self.connect),
            "namespace": self.namespace,
            "seed": self.seed,
            "requested": self.requested,
            "sent": self.sent,
            "bytes": sum(k.bytes for k in self.keys.values()),
            "elapsed_s": round(self.elapsed_s, 3),
            "rate_hz": round(self.sent / self.elapsed_s, 1) if self.elapsed_s > 0 else 0.0,
            "stopped_by": self.stopped_by,
            "targets": len(self.keys),
            "announced_targets": self.announced,
            "kinds": dict(sorted(kinds.items())),
            "replies": {
                "ok": sum(k.replies_ok for k in requests),
                "error": sum(k.replies_err for k in requests),
                "none": sum(k.no_reply for k in requests),
            },
            "decoder_errors": sum(sum(k.decoder_errors.values()) for k in self.keys.values()),
            "skipped_wildcard_keys": self.skipped,
            "keys": {key: report.as_dict() for key, report in sorted(self.keys.items())},
        }

    def to_json(self) -> str:
        return json.dumps(self.as_dict(), indent=2)


def check_loopback(endpoints: Sequence[str]) -> None:
    """Refuse any endpoint that is not on this machine (``ValueError`` naming it)."""
    if not endpoints:
        raise ValueError("give the endpoint to fuzz with --connect")
    for endpoint in endpoints:
        protocol, _, address = endpoint.partition("/")
        address = address.split("?", 1)[0].split("#", 1)[0]
        if protocol in LOCAL_PROTOCOLS:
            continue
        host = address.rsplit(":", 1)[0].strip("[]") if ":" in address else address
        if host in LOOPBACK_NAMES:
            continue
        try:
            if ipaddress.ip_address(host).is_loopback:
                continue
        except ValueError:
            pass
        raise ValueError(f"{endpoint!r} is not a loopback endpoint: zendock fuzz only targets this machine")


def session_spec(options: FuzzOptions) -> SessionSpec:
    return SessionSpec(
        mode="client",
        connect=options.connect,
        config_file=options.zenoh_config,
        overrides=(
            ("connect/timeout_ms", json.dumps(int(options.connect_timeout_s * 1000))),
            ("connect/exit_on_failure", "true"),
        ),
    )


def discover(session: zenoh.Session, namespace: str, timeout_s: float) -> tuple[list[Target], list[str]]:
    """Targets from the live graph and from :mod:`shared.topics`, merged and typed."""
    entries = []
    for reply in session.liveliness().get(f"{GRAPH_PREFIX}/**", timeout=timeout_s):
        if reply.ok is not None:
            entry = parse_token_key(str(reply.ok.key_expr))
            if entry is not None:
                entries.append(entry)
    return merge_targets([*graph_targets(entries, namespace), *known_targets(namespace)], known_types())


class _Requests:
    """Queries in flight: capped, their replies counted per key."""

    def __init__(self, session: zenoh.Session, timeout_s: float, max_in_flight: int) -> None:
        self._session = session
        self._timeout_s = timeout_s
        self._slots = threading.BoundedSemaphore(max_in_flight)
        self._max = max_in_flight
        self._lock = threading.Lock()

    def send(self, target: Target, malformed: Malformed, report: KeyReport, deadline: float) -> bool:
        """Send one query; False when no slot freed up before ``deadline``."""
        if not self._slots.acquire(timeout=max(0.0, deadline - time.monotonic())):
            return False
        replies: list[zenoh.Reply] = []

        def done() -> None:
            with self._lock:
                if not replies:
                    report.no_reply += 1
                for reply in replies:
                    if reply.ok is not None:
                        report.replies_ok += 1
                    else:
                        report.replies_err += 1
            self._slots.release()

        extra: dict[str, Any] = {"encoding": zenoh.Encoding(malformed.encoding)}
        if malformed.payload is not None:
            extra["payload"] = malformed.payload
        try:
            self._session.get(
                target.key,
                zenoh.handlers.Callback(replies.append, done),
                timeout=self._timeout_s,
                target=zenoh.QueryTarget.ALL,
                **extra,
            )
        except Exception:
            self._slots.release()
            raise
        return True

    def drain(self, timeout_s: float) -> None:
        """Wait (bounded) until every query in flight has finished."""
        deadline = time.monotonic() + timeout_s
        taken = 0
        while taken < self._max and self._slots.acquire(timeout=max(0.0, deadline - time.monotonic())):
            taken += 1
        for _ in range(taken):
            self._slots.release()


def fuzz_session(
    session: zenoh.Session,
    options: FuzzOptions,
    progress: Callable[[int, int], None] | None = None,
) -> FuzzReport:
    """Run a campaign on an open session (see the module doc); ``progress(sent, total)`` now and then."""
    started = time.monotonic()
    deadline = started + options.time_limit_s
    targets, skipped = discover(session, options.namespace, options.discovery_timeout_s)
    types: dict[str, type[Message]] = known_types()
    rng = random.Random(options.seed)
    factory = PayloadFactory(rng, types, huge_budget=options.huge_budget)
    report = FuzzReport(options.connect, options.namespace, options.seed, options.messages, skipped=skipped)
    for target in targets:
        report.keys[target.key] = KeyReport(target.key, target.kind, target.type_name, target.announced)
    publishers = {
        t.key: session.declare_publisher(
            t.key, congestion_control=zenoh.CongestionControl.BLOCK, reliability=zenoh.Reliability.RELIABLE
        )
        for t in targets
        if t.kind == TOPIC
    }
    requests = _Requests(session, options.query_timeout_s, options.max_in_flight)
    order: list[Target] = []
    try:
        for i in range(options.messages if targets else 0):
            now = time.monotonic()
            if now >= deadline:
                report.stopped_by = "time limit"
                break
            if options.rate_hz > 0:
                wait_s = started + i / options.rate_hz - now
                if wait_s > 0:
                    time.sleep(min(wait_s, deadline - now))
            if not order:
                order = list(targets)
                rng.shuffle(order)
            target = order.pop()
            malformed = _payload_for(factory, types, target)
            key_report = report.keys[target.key]
            if target.kind == TOPIC:
                publishers[target.key].put(
                    malformed.payload or b"", encoding=zenoh.Encoding(malformed.encoding)
                )
            elif not requests.send(target, malformed, key_report, deadline):
                report.stopped_by = "time limit"
                break
            key_report.sent += 1
            key_report.bytes += malformed.size
            key_report.kinds[malformed.kind] += 1
            if malformed.decoder_error is not None:
                key_report.decoder_errors[f"{target.type_name}: {malformed.decoder_error}"] += 1
            if progress is not None and (i + 1) % 1000 == 0:
                progress(i + 1, options.messages)
        requests.drain(options.query_timeout_s + 2.0)
    finally:
        for publisher in publishers.values():
            publisher.undeclare()
    report.elapsed_s = time.monotonic() - started
    return report


def _payload_for(factory: PayloadFactory, types: dict[str, type[Message]], target: Target) -> Malformed:
    msg_type = types.get(target.type_name) if target.type_name else None
    if msg_type is None:
        return factory.untyped()
    return factory.typed(msg_type, target.empty_request)


def run_fuzz(options: FuzzOptions, progress: Callable[[int, int], None] | None = None) -> FuzzReport:
    """Open a session on the (loopback) endpoint, run the campaign, close the session.

    Raises ``zenoh.ZError`` when no router answers within the connect timeout.
    """
    check_loopback(options.connect)
    with open_session(session_spec(options)) as session:
        return fuzz_session(session, options, progress)
