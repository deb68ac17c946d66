"""A node: one service's publishers, subscriptions, timers and request handlers on a Zenoh session.

Threading model (the contract every service relies on): all user callbacks (subscriptions, timers,
request handlers, replies to asynchronous calls) run one at a time, never concurrently, so service code
needs no locks. Zenoh delivers samples on its own threads; the node decodes them there. When the
executor is idle and nothing is queued, the subscription callback runs at once on that thread, holding
the executor's lock (this saves two thread hand-offs per message); otherwise the message is queued and
:meth:`Node.spin` runs it in order. Timers and request handlers always run on the spinning thread, so
long work belongs in timers. A subscription created with ``inline=True`` always runs on the Zenoh
thread without taking the lock: only for tiny, thread-safe work (the clock).

Input never kills a node: a payload that fails validation is counted and logged once per key per
interval; an exception in a callback is logged with its traceback (rate-limited) and counted.
"""

from __future__ import annotations

import itertools
import json
import logging
import struct
import threading
import time
import traceback
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Generic, TypeVar

import zenoh

from shared.messages import Clock, Time
from shared.names import endpoint_token_key, node_token_key, normalise_namespace, stats_key, topic_key
from shared.ratelimit import RateLimitedLogger
from shared.schema import Message, MessageError

M = TypeVar("M", bound=Message)
Req = TypeVar("Req", bound=Message)
Res = TypeVar("Res", bound=Message)

ENCODING_PREFIX = "application/msgpack"
#: Payloads larger than this are refused before decoding (a 2000 x 2000 map is 4 MB).
MAX_PAYLOAD_BYTES = 8 * 1024 * 1024
_callback_context = threading.local()
_SEQ = struct.Struct("<Q")
_EID = struct.Struct("<I")
#: Every zendock sample's attachment: its sequence number, then its publisher's global id.
ATTACHMENT_SIZE = _SEQ.size + 16 + _EID.size
_PUT = zenoh.SampleKind.PUT


def encoding_for(type_name: str) -> zenoh.Encoding:
    """``application/msgpack`` with the ROS type name as schema."""
    return zenoh.Encoding(f"{ENCODING_PREFIX};{type_name}")


def schema_of(encoding: zenoh.Encoding | None) -> tuple[str, str]:
    """``(mime, schema)`` of a sample's encoding, e.g. ``("application/msgpack", "sensor_msgs/msg/Range")``."""
    text = str(encoding) if encoding is not None else ""
    mime, _, schema = text.partition(";")
    return mime, schema


def publisher_gid(entity: zenoh.EntityGlobalId) -> bytes:
    """20 bytes naming a publisher across the whole system: its session's id, then its entity id."""
    return int(str(entity.zid), 16).to_bytes(16, "little") + _EID.pack(entity.eid)


def sequence_attachment(sequence: int, gid: bytes) -> bytes:
    """The attachment of a zendock sample: the sequence number (u64 little-endian), then the publisher's id.

    One attachment carries both (as rmw_zenoh's does), rather than a sequence attachment plus Zenoh's
    source info: a second extension on every sample cost about 2% of a round trip in ``zendock bench bus``.
    """
    return _SEQ.pack(sequence) + gid


def sequence_number(attachment: zenoh.ZBytes | bytes | None) -> int | None:
    """The per-publisher sequence number a zendock publisher attaches to every sample."""
    raw = _attachment_bytes(attachment)
    return _SEQ.unpack_from(raw)[0] if raw is not None and len(raw) in (_SEQ.size, ATTACHMENT_SIZE) else None


def publisher_id(attachment: zenoh.ZBytes | bytes | None) -> bytes | None:
    """The publisher's id from a zendock sample's attachment (``None`` when the sample has none)."""
    raw = _attachment_bytes(attachment)
    return raw[_SEQ.size:] if raw is not None and len(raw) == ATTACHMENT_SIZE else None


def _attachment_bytes(attachment: zenoh.ZBytes | bytes | None) -> bytes | None:
    return attachment if attachment is None or isinstance(attachment, bytes) else attachment.to_bytes()


@dataclass(frozen=True)
class QoS:
    """Delivery policy mapped onto Zenoh.

    Publisher side: ``reliable`` (Zenoh reliability), ``block`` (congestion control BLOCK instead of DROP:
    never lose a message, at the cost of stalling the sender) and ``express`` (send without batching).
    Subscriber side: ``depth``, how many unprocessed messages a subscription keeps (keep-last: the oldest
    are dropped and counted). Zenoh decides reliability at the sender, so a subscription's ``reliable``
    has no effect.
    """

    reliable: bool = True
    block: bool = False
    depth: int = 10
    express: bool = False


#: Commands and state: reliable, keep the last ten.
RELIABLE = QoS()
#: Sensor streams: best effort, drop under congestion, keep the latest few (ROS SensorDataQoS).
SENSOR_DATA = QoS(reliable=False, block=False, depth=5, express=True)
#: Nothing may be lost (maps, action results).
BLOCKING = QoS(reliable=True, block=True, depth=100)


class ServiceError(RuntimeError):
    """A request failed: nothing answered, it timed out, or the server rejected it (reason given)."""


class ServiceUnavailable(ServiceError):
    """Nothing answered the request in time: no server, or one restarting. Asking again may work."""


@dataclass(frozen=True)
class ServiceType(Generic[Req, Res]):
    """A request/response interface, e.g. ``zendock_msgs/srv/Teleport``."""

    type_name: str
    request: type[Req]
    response: type[Res]


@dataclass
class NodeStats:
    """Counters a test or a tool can read: what arrived, what was rejected, what failed."""

    received: dict[str, int] = field(default_factory=dict)
    #: Samples put per key by this node's publishers.
    published: dict[str, int] = field(default_factory=dict)
    rejected: dict[str, int] = field(default_factory=dict)
    dropped: dict[str, int] = field(default_factory=dict)
    callback_errors: int = 0
    #: A service's own measures, reported with the counters (the simulator's waits for late drivers).
    extra: dict[str, float] = field(default_factory=dict)


class _Executor:
    """Runs queued work and due timers on one thread, in order."""

    def __init__(self, node: Node) -> None:
        self._node = node
        self._cv = threading.Condition()
        self._ready: deque[tuple[Callable[..., Any], tuple[Any, ...]]] = deque()
        self._stop = False
        self._timers: list[Timer] = []
        #: Held while any callback runs: callbacks are mutually exclusive whatever thread runs them.
        self.run_lock = threading.Lock()
        #: The earliest sim time a sim-time timer is due; the clock wakes the executor only from then on.
        self.next_sim_due = 0.0

    def post(self, fn: Callable[..., Any], *args: Any) -> None:
        with self._cv:
            self._ready.append((fn, args))
            self._cv.notify()

    def wake(self) -> None:
        with self._cv:
            self._cv.notify()

    def add_timer(self, timer: Timer) -> None:
        with self._cv:
            self._timers.append(timer)
            self.next_sim_due = 0.0  # let the clock wake us to schedule the new timer
            self._cv.notify()

    def remove_timer(self, timer: Timer) -> None:
        with self._cv:
            if timer in self._timers:
                self._timers.remove(timer)

    def stop(self) -> None:
        with self._cv:
            self._stop = True
            self._cv.notify_all()

    @property
    def stopped(self) -> bool:
        return self._stop

    def spin(self, until: Callable[[], bool] | None = None, timeout_s: float | None = None) -> bool:
        """Run until stopped, until ``until()`` is true, or until the wall timeout; returns ``until()``'s value."""
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while True:
            if until is not None and until():
                return True
            with self._cv:
                if self._stop:
                    return False
                wait = self._next_wall_wait()
                if deadline is not None:
                    wait = min(wait, deadline - time.monotonic())
                    if wait <= 0 and not self._ready:
                        return bool(until and until())
                if not self._ready and wait > 0:
                    self._cv.wait(min(wait, 0.1))
                work = list(self._ready)
                self._ready.clear()
                timers = list(self._timers)
            with self.run_lock:
                for fn, args in work:
                    self._node._run_callback(fn, *args)
                for timer in timers:
                    if timer.due():
                        self._node._run_callback(timer.fire)
                sim_deadlines = [t.next_due for t in timers if t.uses_sim_time and not t.cancelled]
                self.next_sim_due = min((d if d is not None else 0.0 for d in sim_deadlines), default=float("inf"))

    def _next_wall_wait(self) -> float:
        wait = 0.1
        for timer in self._timers:
            if not timer.uses_sim_time:
                wait = min(wait, timer.wall_wait())
        return max(wait, 0.0)


#: A timer is due this close before its deadline: sim time is a count of steps times the step (1.05 may be
#: 1.0499999999999998) while deadlines add up periods, so a tick that lands exactly on a deadline must count
#: as on time, or a 20 Hz timer on a 20 Hz clock would fire on every other tick.
TIMER_TOLERANCE_S = 1e-6


class Timer:
    """Calls ``callback`` every ``period_s`` on the node's clock (sim time when the node uses it)."""

    def __init__(self, node: Node, period_s: float, callback: Callable[[], Any], uses_sim_time: bool) -> None:
        if not period_s > 0:
            raise ValueError(f"timer period must be positive, got {period_s}")
        self._node = node
        self.period_s = period_s
        self._callback = callback
        self.uses_sim_time = uses_sim_time
        self._next: float | None = None
        self.cancelled = False

    def _now(self) -> float:
        return self._node.now() if self.uses_sim_time else time.monotonic()

    def due(self) -> bool:
        if self.cancelled:
            return False
        now = self._now()
        if self.uses_sim_time and not self._node.clock_started:
            return False
        if self._next is None or now < self._next - 2 * self.period_s - 1.0:
            self._next = now + self.period_s  # first tick, or the clock jumped back (simulator reset)
            return False
        return now >= self._next - TIMER_TOLERANCE_S

    @property
    def next_due(self) -> float | None:
        """When the timer fires next on its clock (``None`` before its first tick is scheduled)."""
        return self._next

    def wall_wait(self) -> float:
        if self._next is None:
            return 0.0
        return self._next - time.monotonic()

    def fire(self) -> None:
        now = self._now()
        assert self._next is not None
        self._next += self.period_s
        if self._next <= now:  # fell behind: skip the missed ticks rather than bursting
            self._next = now + self.period_s
        self._callback()

    def cancel(self) -> None:
        self.cancelled = True
        self._node._executor.remove_timer(self)


class Publisher(Generic[M]):
    """Publishes one message type on one key; refuses invalid messages at the sender."""

    def __init__(self, node: Node, msg_type: type[M], topic: str, qos: QoS) -> None:
        self.msg_type = msg_type
        self.key = node.key(topic)
        self.qos = qos
        self._encoding = encoding_for(msg_type.TYPE_NAME)
        self._publisher = node.session.declare_publisher(
            self.key,
            encoding=self._encoding,
            reliability=zenoh.Reliability.RELIABLE if qos.reliable else zenoh.Reliability.BEST_EFFORT,
            congestion_control=zenoh.CongestionControl.BLOCK if qos.block else zenoh.CongestionControl.DROP,
            express=qos.express,
        )
        self._put = self._publisher.put
        self._seq = itertools.count(1)
        self._lock = threading.Lock()
        self._gid = publisher_gid(self._publisher.id)
        self._published = node.stats.published
        self._token = node._declare_endpoint("pub", msg_type.TYPE_NAME, self.key)

    def publish(self, msg: M) -> None:
        if type(msg) is not self.msg_type and not isinstance(msg, self.msg_type):
            raise MessageError(f"publisher expects {self.msg_type.TYPE_NAME}, got {type(msg).__name__}", key=self.key)
        try:
            payload = msg.encode()
        except MessageError as exc:
            raise exc.at(key=self.key) from None
        self.publish_encoded(payload)

    def publish_encoded(self, payload: bytes) -> None:
        """Put an already validated payload (replay, relays).

        Every sample's attachment carries its sequence number and the publisher's id
        (:func:`sequence_attachment`), so a recorder counts losses per publisher. The encoding was
        declared once with the publisher, so no put passes (or builds) it.
        """
        with self._lock:  # the put order is the sequence order, whichever threads publish
            self._put(payload, attachment=sequence_attachment(next(self._seq), self._gid))
            self._published[self.key] = self._published.get(self.key, 0) + 1

    def has_subscribers(self) -> bool:
        """Whether any subscriber matches this key now (Zenoh's matching status), so costly messages such as
        images are made only while someone listens."""
        status: Any = self._publisher.matching_status  # a MatchingStatus (the stub says bool)
        return bool(status.matching)

    def undeclare(self) -> None:
        self._token.undeclare()
        self._publisher.undeclare()


class Subscription(Generic[M]):
    """Receives one message type on one key (wildcards allowed) and hands valid messages to a callback.

    The callback gets the decoded message; with ``with_key=True`` it gets ``(key, message)``.
    """

    def __init__(
        self,
        node: Node,
        msg_type: type[M],
        topic: str,
        callback: Callable[..., Any],
        qos: QoS,
        inline: bool,
        with_key: bool,
        absolute: bool = False,
    ) -> None:
        self._node = node
        self.msg_type = msg_type
        self.key = topic if absolute else node.key(topic)
        self._callback = callback
        self._inline = inline
        self._with_key = with_key
        self._queue: deque[tuple[str, M]] = deque(maxlen=max(1, qos.depth))
        self._scheduled = False
        self._lock = threading.Lock()
        self._encoding = encoding_for(msg_type.TYPE_NAME)
        self._decode = msg_type.decode
        #: Without wildcards every sample's key is the subscription's own key: no need to read it back.
        self._exact_key = "" if "*" in self.key else self.key
        self._subscriber = node.session.declare_subscriber(self.key, self._on_sample)
        self._token = node._declare_endpoint("sub", msg_type.TYPE_NAME, self.key)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        # The hot path of every message: each attribute read of a sample makes a new object, and on a busy
        # machine this code runs with cold caches, so it reads each only once and skips what it can.
        payload = sample.payload
        size = len(payload)
        if not size and sample.kind != _PUT:  # a DELETE (never a message): it has no payload
            return
        key = self._exact_key or str(sample.key_expr)
        node = self._node
        try:
            encoding = sample.encoding
            if encoding != self._encoding:  # one comparison in Rust for the common case
                mime, schema = schema_of(encoding)
                if schema and schema != self.msg_type.TYPE_NAME and mime == ENCODING_PREFIX:
                    raise MessageError(f"expected type {self.msg_type.TYPE_NAME}, got {schema}", key=key)
            if size > MAX_PAYLOAD_BYTES:
                raise MessageError(f"payload of {size} bytes exceeds {MAX_PAYLOAD_BYTES}", key=key)
            msg = self._decode(payload.to_bytes())
        except MessageError as exc:
            node._reject(key, exc.at(key=key))
            return
        received = node.stats.received
        received[key] = received.get(key, 0) + 1
        if self._inline:
            node._run_callback(self._deliver, key, msg)
            return
        executor = node._executor
        # Direct dispatch when nothing is queued anywhere (so order is kept) and no callback runs.
        # zenoh-python calls one subscription's callback from one thread, so our own state needs no lock.
        if not (self._scheduled or self._queue or executor._ready or executor._stop) and executor.run_lock.acquire(False):
            context = _callback_context
            outer = getattr(context, "active", False)
            context.active = True
            try:
                if self._with_key:
                    self._callback(key, msg)
                else:
                    self._callback(msg)
            except Exception as exc:
                node._log_callback_error(exc)
            finally:
                context.active = outer
                executor.run_lock.release()
            return
        with self._lock:
            if len(self._queue) == self._queue.maxlen:
                node._count(node.stats.dropped, key)
            self._queue.append((key, msg))
            if self._scheduled:
                return
            self._scheduled = True
        executor.post(self._drain)

    def _drain(self) -> None:
        while True:
            with self._lock:
                if not self._queue:
                    self._scheduled = False
                    return
                key, msg = self._queue.popleft()
            self._node._run_callback(self._deliver, key, msg)

    def _deliver(self, key: str, msg: M) -> None:
        if self._with_key:
            self._callback(key, msg)
        else:
            self._callback(msg)

    def undeclare(self) -> None:
        """Stop receiving (a subscription a node declares and drops as its needs change)."""
        self._token.undeclare()
        self._subscriber.undeclare()
        self._node._forget(self, self._token)


class ServiceServer(Generic[Req, Res]):
    """Answers requests on ``<ns>/<name>`` (a Zenoh queryable); the handler runs on the executor.

    The handler returns a response message, or raises :class:`ServiceError` / ``ValueError`` to reply
    with an error that names the reason. Malformed requests are rejected before the handler sees them.
    """

    def __init__(self, node: Node, srv: ServiceType[Req, Res], name: str, handler: Callable[[Req], Res]) -> None:
        self._node = node
        self.srv = srv
        self.key = node.key(name)
        self._handler = handler
        self._queryable = node.session.declare_queryable(self.key, self._on_query)
        self._token = node._declare_endpoint("srv", srv.type_name, self.key)

    def _on_query(self, query: zenoh.Query) -> None:
        payload = query.payload
        try:
            request = self.srv.request.decode(payload.to_bytes() if payload is not None else b"\x80")
        except MessageError as exc:
            self._node._reject(self.key, exc.at(key=self.key))
            query.reply_err(str(exc).encode(), encoding=zenoh.Encoding("text/plain"))
            query.drop()
            return
        self._node._executor.post(self._answer, query, request)

    def _answer(self, query: zenoh.Query, request: Req) -> None:
        try:
            response = self._handler(request)
            if not isinstance(response, self.srv.response):
                raise ServiceError(f"handler returned {type(response).__name__}, expected {self.srv.response.__name__}")
            query.reply(self.key, response.encode(), encoding=encoding_for(self.srv.response.TYPE_NAME))
        except (ServiceError, ValueError) as exc:
            query.reply_err(str(exc).encode(), encoding=zenoh.Encoding("text/plain"))
        except Exception as exc:  # a bug in a handler: answer, log, keep serving
            query.reply_err(f"internal error: {type(exc).__name__}: {exc}".encode(), encoding=zenoh.Encoding("text/plain"))
            self._node._log_callback_error(exc)
        finally:
            query.drop()

    def undeclare(self) -> None:
        self._token.undeclare()
        self._queryable.undeclare()


def _decode_reply(srv: ServiceType[Any, Res], key: str, reply: zenoh.Reply) -> Res:
    if reply.ok is None:
        err = reply.err
        text = err.payload.to_string() if err is not None else "no reason given"
        raise ServiceError(f"{key}: {text}")
    try:
        return srv.response.decode(reply.ok.payload.to_bytes())
    except MessageError as exc:
        raise ServiceError(f"{key}: malformed response: {exc}") from None


def call_service(
    session: zenoh.Session, key: str, srv: ServiceType[Req, Res], request: Req, timeout_s: float = 5.0
) -> Res:
    """Blocking request/response on a bare session (tools, tests). Raises :class:`ServiceError`."""
    payload = request.encode()
    replies = list(
        session.get(
            key,
            payload=payload,
            encoding=encoding_for(srv.request.TYPE_NAME),
            timeout=timeout_s,
            target=zenoh.QueryTarget.BEST_MATCHING,
        )
    )
    if not replies:
        raise ServiceUnavailable(f"{key}: no service answered within {timeout_s:g} s")
    return _decode_reply(srv, key, replies[0])


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
        self._executor = _Executor(self)
        self._tokens: list[zenoh.LivelinessToken] = []
        self._entities: list[Any] = []
        self._node_token: zenoh.LivelinessToken | None = None
        self._stats_queryable: Any = None
        self._sim_now = 0.0
        self.clock_started = False
        self._clock_sub: Subscription[Clock] | None = None
        if use_sim_time:
            self._clock_sub = self.create_subscription(Clock, "clock", self._on_clock, QoS(depth=1), inline=True)

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
    ) -> Subscription[M]:
        """Subscribe to ``topic`` in the node's namespace (``absolute=True``: ``topic`` is a full key)."""
        sub = Subscription(self, msg_type, topic, callback, qos, inline, with_key, absolute)
        self._entities.append(sub)
        return sub

    def create_timer(self, period_s: float, callback: Callable[[], Any], *, wall: bool = False) -> Timer:
        """A periodic callback on sim time when the node uses it (``wall=True`` forces wall time)."""
        timer = Timer(self, period_s, callback, uses_sim_time=self.use_sim_time and not wall)
        self._executor.add_timer(timer)
        return timer

    def create_service(
        self, srv: ServiceType[Req, Res], name: str, handler: Callable[[Req], Res]
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
                self._executor.post(on_done, None, ServiceUnavailable(f"{key}: no service answered within {timeout_s:g} s"))
                return
            try:
                response = _decode_reply(srv, key, replies[0])
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
        if getattr(_callback_context, "active", False):
            raise RuntimeError("Node.call would block the node's callbacks; use call_async from callbacks")
        return call_service(self.session, self.key(name), srv, request, timeout_s)

    def post(self, fn: Callable[..., Any], *args: Any) -> None:
        """Run ``fn(*args)`` on the executor (from any thread)."""
        self._executor.post(fn, *args)

    def exclusive(self) -> threading.Lock:
        """A context manager: code in it never runs at the same time as this node's callbacks.

        For a service's own loop thread (the simulator's stepping loop) that shares state with callbacks.
        """
        return self._executor.run_lock

    # --- graph -------------------------------------------------------------------------------------

    def _declare_endpoint(self, kind: str, type_name: str, key: str) -> zenoh.LivelinessToken:
        token = self.session.liveliness().declare_token(
            endpoint_token_key(kind, self.namespace, self.name, type_name, key)
        )
        self._tokens.append(token)
        return token

    def _forget(self, entity: Any, token: zenoh.LivelinessToken) -> None:
        """Drop an undeclared entity and its endpoint token, so declaring and dropping never accumulates."""
        self._entities = [e for e in self._entities if e is not entity]
        self._tokens = [t for t in self._tokens if t is not token]

    def declare_ready(self) -> None:
        """Announce the node (its liveliness token): launchers treat this as healthy. From then on the node
        also answers ``@zendock/stats/<ns>/<node>`` with its message counters (JSON)."""
        if self._node_token is None:
            self._node_token = self.session.liveliness().declare_token(node_token_key(self.namespace, self.name))
            self._stats_queryable = self.session.declare_queryable(stats_key(self.namespace, self.name),
                                                                   self._on_stats_query)

    def _on_stats_query(self, query: zenoh.Query) -> None:
        """Zenoh's thread: copies of the counters (dict copies are atomic enough under the GIL), one reply."""
        stats = self.stats
        body = {"node": self.name, "namespace": self.namespace, "published": dict(stats.published),
                "received": dict(stats.received), "dropped": dict(stats.dropped), "rejected": dict(stats.rejected),
                "callback_errors": stats.callback_errors, "extra": dict(stats.extra), "now": self.now()}
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

    # --- internals ---------------------------------------------------------------------------------

    @staticmethod
    def _count(table: dict[str, int], key: str) -> None:
        table[key] = table.get(key, 0) + 1

    def _reject(self, key: str, error: MessageError) -> None:
        self._count(self.stats.rejected, key)
        n = self.stats.rejected[key]
        self._ratelimited.warning(f"reject:{key}", "rejected message on %s (%d so far): %s", key, n, error)

    def _run_callback(self, fn: Callable[..., Any], *args: Any) -> None:
        outer = getattr(_callback_context, "active", False)
        _callback_context.active = True
        try:
            fn(*args)
        except Exception as exc:
            self._log_callback_error(exc)
        finally:
            _callback_context.active = outer

    def _log_callback_error(self, exc: BaseException) -> None:
        self.stats.callback_errors += 1
        where = traceback.extract_tb(exc.__traceback__)[-1] if exc.__traceback__ else None
        site = f"{where.filename}:{where.lineno}" if where else "?"
        self._ratelimited.error(
            f"callback:{site}", "callback failed (%d so far): %s: %s\n%s",
            self.stats.callback_errors, type(exc).__name__, exc, "".join(traceback.format_exception(exc)).rstrip(),
        )

