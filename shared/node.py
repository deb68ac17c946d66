"""A node: one service's publishers, subscriptions, timers and request handlers on a Zenoh session.

Threading model (the contract every service relies on): all user callbacks (subscriptions, timers,
request handlers, replies to asynchronous calls) run one at a time, never concurrently, so service code
needs no locks. Zenoh delivers samples on its own threads; the node decodes them there. When the
executor is idle and nothing is queued, the subscription callback runs at once on that thread, holding
the executor's lock (this saves two thread hand-offs per message); otherwise the message is queued and
:meth:`Node.spin` runs it in order. Timers and request handlers always run on the spinning thread, so
long work belongs in timers. A subscription created with ``inline=True`` always runs on the Zenoh
thread without taking the lock: only for tiny, thread-safe work (the clock). :mod:`shared.executor`
keeps this rule, in one place; :mod:`shared.endpoints` holds the publishers, subscriptions and servers
and :mod:`shared.encoding` the samples' encoding and attachment. This module re-exports their public
names, so ``from shared.node import ...`` is all a service needs.

Input never kills a node: a payload that fails validation is counted and logged once per key per
interval; an exception in a callback is logged with its traceback (rate-limited) and counted.
"""

from __future__ import annotations

import json
import logging
import threading
import time
import traceback
from collections.abc import Callable
from typing import Any, TypeVar

import msgspec
import zenoh

from shared.encoding import (
    ANSWERING_ATTACHMENT_SIZE,
    ATTACHMENT_SIZE,
    ENCODING_PREFIX,
    MAX_PAYLOAD_BYTES,
    answered_tick_s,
    encoding_for,
    publisher_gid,
    publisher_id,
    schema_of,
    sequence_attachment,
    sequence_number,
)
from shared.endpoints import (
    BLOCKING,
    RELIABLE,
    SENSOR_DATA,
    Deferred,
    Publisher,
    QoS,
    ServiceError,
    ServiceServer,
    ServiceUnavailable,
    Subscription,
    call_service,
    decode_reply,
)
from shared.executor import TIMER_TOLERANCE_S, Executor, Timer, in_callback
from shared.interface_types import ServiceType
from shared.messages import Clock, Time
from shared.names import endpoint_token_key, node_token_key, normalise_namespace, stats_key, topic_key
from shared.ratelimit import RateLimitedLogger
from shared.schema import Message, MessageError

__all__ = [
    "ANSWERING_ATTACHMENT_SIZE",
    "ATTACHMENT_SIZE",
    "BLOCKING",
    "ENCODING_PREFIX",
    "MAX_PAYLOAD_BYTES",
    "RELIABLE",
    "SENSOR_DATA",
    "TIMER_TOLERANCE_S",
    "Node",
    "NodeStats",
    "Publisher",
    "QoS",
    "ServiceError",
    "ServiceServer",
    "ServiceType",
    "ServiceUnavailable",
    "Subscription",
    "Timer",
    "answered_tick_s",
    "call_service",
    "encoding_for",
    "publisher_gid",
    "publisher_id",
    "schema_of",
    "sequence_attachment",
    "sequence_number",
]

M = TypeVar("M", bound=Message)
Req = TypeVar("Req", bound=Message)
Res = TypeVar("Res", bound=Message)


class NodeStats(msgspec.Struct):
    """Counters a test or a tool can read: what arrived, what was rejected, what failed."""

    received: dict[str, int] = msgspec.field(default_factory=dict)
    #: Samples put per key by this node's publishers.
    published: dict[str, int] = msgspec.field(default_factory=dict)
    rejected: dict[str, int] = msgspec.field(default_factory=dict)
    dropped: dict[str, int] = msgspec.field(default_factory=dict)
    callback_errors: int = 0
    #: A service's own measures, reported with the counters (the simulator's waits for late drivers).
    extra: dict[str, float] = msgspec.field(default_factory=dict)


class Node:
    """One service's presence on the bus. Use as a context manager or call :meth:`close`."""

    def __init__(
        self,
        name: str,
        session: zenoh.Session,
        namespace: str = "",
        use_sim_time: bool = False,
        logger: logging.Logger | None = None,
    ) -> None:
        self.name = name
        self.session = session
        self.namespace = normalise_namespace(namespace)
        self.use_sim_time = use_sim_time
        self.log = logger or logging.getLogger(name)
        self.stats = NodeStats()
        self._ratelimited = RateLimitedLogger(self.log, interval_s=5.0)
        self._executor = Executor(on_error=self._log_callback_error)
        self._tokens: list[zenoh.LivelinessToken] = []
        self._entities: list[Any] = []
        self._node_token: zenoh.LivelinessToken | None = None
        self._stats_queryable: Any = None
        self._sim_now = 0.0
        self.clock_started = False
        #: Called with ``(kind, type name, key)`` before each endpoint is declared (the service's contract,
        #: :mod:`shared.contracts.enforce`); it raises to refuse one.
        self.endpoint_check: Callable[[str, str, str], None] | None = None
        #: This node's action servers by name, for whoever must reach a running goal (a lifecycle change).
        self.action_servers: dict[str, Any] = {}
        #: Asked before an action server accepts a goal: the reason to refuse it, or None
        #: (the Nav2 stand-ins' lifecycle, :mod:`shared.lifecycle_states`).
        self.work_gate: Callable[[str], str | None] | None = None
        self._clock_sub: Subscription[Clock] | None = None
        if use_sim_time:
            self._clock_sub = self.create_subscription(
                Clock, "clock", self._on_clock, QoS(depth=1), inline=True
            )

    # --- naming and time ---------------------------------------------------------------------------

    def key(self, topic: str) -> str:
        return topic_key(self.namespace, topic)

    def now(self) -> float:
        """Seconds on the node's clock: sim time (0 until the first clock message) or wall time."""
        return self._sim_now if self.use_sim_time else time.time()

    def now_msg(self) -> Time:
        return Time.from_sec(self.now())

    def _on_clock(self, msg: Clock) -> None:
        now = msg.clock.to_sec()
        jumped_back = now < self._sim_now
        self._sim_now = now
        self.clock_started = True
        # Wake the executor only when a sim-time timer is due (or time jumped back: a simulator restart),
        # not on every tick of the clock.
        if now >= self._executor.next_sim_due - TIMER_TOLERANCE_S or jumped_back:
            self._executor.wake()

    # --- entities ----------------------------------------------------------------------------------

    def create_publisher(self, msg_type: type[M], topic: str, qos: QoS = RELIABLE) -> Publisher[M]:
        pub = Publisher(self, msg_type, topic, qos)
        self._entities.append(pub)
        return pub

    def create_subscription(
        self,
        msg_type: type[M],
        topic: str,
        callback: Callable[..., Any],
        qos: QoS = RELIABLE,
        *,
        inline: bool = False,
        with_key: bool = False,
        absolute: bool = False,
        undecoded: bool = False,
        with_answered: bool = False,
    ) -> Subscription[M]:
        """Subscribe to ``topic`` in the node's namespace (``absolute=True``: ``topic`` is a full key;
        ``undecoded=True``: the callback gets the payload's bytes; ``with_answered=True``: it gets the
        control tick a command answers too; see :class:`Subscription`)."""
        sub = Subscription(
            self, msg_type, topic, callback, qos, inline, with_key, absolute, undecoded, with_answered
        )
        self._entities.append(sub)
        return sub

    def create_timer(self, period_s: float, callback: Callable[[], Any], *, wall: bool = False) -> Timer:
        """A periodic callback on sim time when the node uses it (``wall=True`` forces wall time)."""
        timer = Timer(
            self._executor, period_s, callback, sim_clock=self if self.use_sim_time and not wall else None
        )
        self._executor.add_timer(timer)
        return timer

    def create_service(
        self, srv: ServiceType[Req, Res], name: str, handler: Callable[[Req], Res | Deferred[Res]]
    ) -> ServiceServer[Req, Res]:
        server = ServiceServer(self, srv, name, handler)
        self._entities.append(server)
        return server

    def call_async(
        self,
        srv: ServiceType[Req, Res],
        name: str,
        request: Req,
        on_done: Callable[[Res | None, ServiceError | None], Any],
        timeout_s: float = 5.0,
        *,
        absolute: bool = False,
    ) -> None:
        """Send a request without blocking; ``on_done(response, error)`` runs later on the executor.
        ``absolute``: ``name`` is a full key, not a name in the node's namespace."""
        key = name if absolute else self.key(name)
        try:
            payload = request.encode()
        except MessageError as exc:
            raise exc.at(key=key) from None
        replies: list[zenoh.Reply] = []

        def finished() -> None:
            if not replies:
                self._executor.post(
                    on_done, None, ServiceUnavailable(f"{key}: no service answered within {timeout_s:g} s")
                )
                return
            try:
                response = decode_reply(srv, key, replies[0])
            except ServiceError as exc:
                self._executor.post(on_done, None, exc)
                return
            self._executor.post(on_done, response, None)

        self.session.get(
            key,
            zenoh.handlers.Callback(replies.append, finished),
            payload=payload,
            encoding=encoding_for(srv.request.TYPE_NAME),
            timeout=timeout_s,
            target=zenoh.QueryTarget.BEST_MATCHING,
        )

    def call(self, srv: ServiceType[Req, Res], name: str, request: Req, timeout_s: float = 5.0) -> Res:
        """Blocking request; never from this node's callbacks (use :meth:`call_async` there)."""
        if in_callback():
            raise RuntimeError("Node.call would block the node's callbacks; use call_async from callbacks")
        return call_service(self.session, self.key(name), srv, request, timeout_s)

    def post(self, fn: Callable[..., Any], *args: Any) -> None:
        """Run ``fn(*args)`` on the executor (from any thread)."""
        self._executor.post(fn, *args)

    def exclusive(self) -> threading.Lock:
        """A context manager: code in it never runs at the same time as this node's callbacks.

        For a service's own loop thread (the simulator's stepping loop) that shares state with callbacks.
        """
        return self._executor.exclusive()

    # --- graph -------------------------------------------------------------------------------------

    @property
    def executor(self) -> Executor:
        """Where this node's callbacks run (:mod:`shared.executor`); endpoints hand their work to it."""
        return self._executor

    def declare_endpoint(self, kind: str, type_name: str, key: str) -> zenoh.LivelinessToken:
        """Announce one of this node's endpoints (``pub``, ``sub``, ``srv``, ``act``) in the graph; the token
        is undeclared with the node."""
        if self.endpoint_check is not None:
            self.endpoint_check(kind, type_name, key)
        token = self.session.liveliness().declare_token(
            endpoint_token_key(kind, self.namespace, self.name, type_name, key)
        )
        self._tokens.append(token)
        return token

    def forget(self, entity: Any, token: zenoh.LivelinessToken) -> None:
        """Drop an undeclared entity and its endpoint token, so declaring and dropping never accumulates."""
        self._entities = [e for e in self._entities if e is not entity]
        self._tokens = [t for t in self._tokens if t is not token]

    def declare_ready(self) -> None:
        """Announce the node (its liveliness token): launchers treat this as healthy. From then on the node
        also answers ``@zendock/stats/<ns>/<node>`` with its message counters (JSON)."""
        if self._node_token is None:
            self._node_token = self.session.liveliness().declare_token(
                node_token_key(self.namespace, self.name)
            )
            self._stats_queryable = self.session.declare_queryable(
                stats_key(self.namespace, self.name), self._on_stats_query
            )

    def _on_stats_query(self, query: zenoh.Query) -> None:
        """Zenoh's thread: copies of the counters (dict copies are atomic enough under the GIL), one reply."""
        stats = self.stats
        body = {
            "node": self.name,
            "namespace": self.namespace,
            "published": dict(stats.published),
            "received": dict(stats.received),
            "dropped": dict(stats.dropped),
            "rejected": dict(stats.rejected),
            "callback_errors": stats.callback_errors,
            "extra": dict(stats.extra),
            "now": self.now(),
        }
        try:
            query.reply(query.key_expr, json.dumps(body))
        except zenoh.ZError:  # the querier left
            pass

    # --- running -----------------------------------------------------------------------------------

    def spin(self, until: Callable[[], bool] | None = None, timeout_s: float | None = None) -> bool:
        """Run callbacks on this thread until :meth:`shutdown` (or ``until()``/timeout); see the module doc."""
        return self._executor.spin(until, timeout_s)

    def shutdown(self) -> None:
        """Stop :meth:`spin` (safe from signal handlers and other threads)."""
        self._executor.stop()

    def close(self) -> None:
        self.shutdown()
        for entity in self._entities:
            if isinstance(entity, Subscription):
                entity.close()  # a subscriber shared with other nodes outlives this one's membership
        if self._stats_queryable is not None:
            try:
                self._stats_queryable.undeclare()
            except Exception:  # the session may already be closing
                pass
            self._stats_queryable = None
        for token in [self._node_token, *self._tokens]:
            if token is not None:
                try:
                    token.undeclare()
                except Exception:  # the session may already be closing
                    pass
        self._tokens.clear()
        self._node_token = None

    def __enter__(self) -> Node:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- failures ----------------------------------------------------------------------------------

    def reject(self, key: str, error: MessageError) -> None:
        """Count and log (rate-limited, per key) a payload on ``key`` that failed validation."""
        rejected = self.stats.rejected
        rejected[key] = n = rejected.get(key, 0) + 1
        self._ratelimited.warning(f"reject:{key}", "rejected message on %s (%d so far): %s", key, n, error)

    def _log_callback_error(self, exc: BaseException) -> None:
        """The executor's error reporter: count a failed callback, log it with its traceback (rate-limited)."""
        self.stats.callback_errors += 1
        where = traceback.extract_tb(exc.__traceback__)[-1] if exc.__traceback__ else None
        site = f"{where.filename}:{where.lineno}" if where else "?"
        self._ratelimited.error(
            f"callback:{site}",
            "callback failed (%d so far): %s: %s\n%s",
            self.stats.callback_errors,
            type(exc).__name__,
            exc,
            "".join(traceback.format_exception(exc)).rstrip(),
        )
