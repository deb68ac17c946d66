"""A node's endpoints on the bus: publishers, subscriptions, service servers, and requests.

Each endpoint validates at its edge: a publisher refuses an invalid message at the sender; a subscription
or a server decodes on Zenoh's thread and rejects (counts and logs, through its node) a payload that
fails validation, so callbacks only ever see valid messages. When a callback runs is the executor's
business (:mod:`shared.executor`): a subscription offers each message to :meth:`Executor.try_run_now
<shared.executor.Executor.try_run_now>` and queues it when the executor declines.
"""

from __future__ import annotations

import functools
import itertools
import threading
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Generic, TypeVar

import msgspec
import zenoh

from shared.encoding import (
    ENCODING_PREFIX,
    MAX_PAYLOAD_BYTES,
    answered_tick_s,
    encoding_for,
    publisher_gid,
    schema_of,
    sequence_attachment,
)
from shared.executor import Work
from shared.interface_types import ServiceType
from shared.schema import Message, MessageError
from shared.subscriber_hub import SUBSCRIBER_HUB

if TYPE_CHECKING:
    from shared.node import Node

M = TypeVar("M", bound=Message)
Req = TypeVar("Req", bound=Message)
Res = TypeVar("Res", bound=Message)

_PUT = zenoh.SampleKind.PUT


class QoS(msgspec.Struct, frozen=True):
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
        self._token = node.declare_endpoint("pub", msg_type.TYPE_NAME, self.key)
        self._matching_listeners: list[Any] = []

    def publish(self, msg: M, *, answers_s: float | None = None) -> None:
        """Put ``msg``; ``answers_s``: the sim time of the control tick a command was computed on, carried in
        the attachment so the simulator's lockstep holds the world for the command of each step."""
        if type(msg) is not self.msg_type and not isinstance(msg, self.msg_type):
            raise MessageError(
                f"publisher expects {self.msg_type.TYPE_NAME}, got {type(msg).__name__}", key=self.key
            )
        try:
            payload = msg.encode()
        except MessageError as exc:
            raise exc.at(key=self.key) from None
        self.publish_encoded(payload, answers_s=answers_s)

    def publish_encoded(self, payload: bytes, *, answers_s: float | None = None) -> None:
        """Put an already validated payload (replay, relays).

        Every sample's attachment carries its sequence number and the publisher's id
        (:func:`~shared.encoding.sequence_attachment`), so a recorder counts losses per publisher. The
        encoding was declared once with the publisher, so no put passes (or builds) it.
        """
        with self._lock:  # the put order is the sequence order, whichever threads publish
            self._put(payload, attachment=sequence_attachment(next(self._seq), self._gid, answers_s))
            self._published[self.key] = self._published.get(self.key, 0) + 1

    def has_subscribers(self) -> bool:
        """Whether any subscriber matches this key now (Zenoh's matching status), so costly messages such as
        images are made only while someone listens."""
        status: Any = self._publisher.matching_status  # a MatchingStatus (the stub says bool)
        return bool(status.matching)

    def on_matching_change(self, callback: Callable[[bool], Any]) -> None:
        """Call ``callback(matching)`` whenever subscribers to this key appear (True) or all go (False).

        Zenoh calls it on one of its own threads, as soon as the router tells of the change: a service that
        makes costly messages only on demand follows the demand at once instead of polling for it.
        """
        listener: Any = self._publisher.declare_matching_listener(
            lambda status: callback(bool(status.matching))
        )
        self._matching_listeners.append(listener)  # a listener lives as long as its reference

    def undeclare(self) -> None:
        for listener in self._matching_listeners:
            listener.undeclare()
        self._matching_listeners.clear()
        self._token.undeclare()
        self._publisher.undeclare()


def _payload_bytes(_key: str, data: bytes) -> bytes:
    return data


#: Payloads up to this size are remembered once decoded (a scan is about 3 kB; camera images are not kept).
SHARED_DECODE_MAX_BYTES = 16384
#: Remembered keys at most: a process subscribes to a few dozen; past this the memory starts afresh.
SHARED_DECODE_MAX_KEYS = 512


class SharedDecodes:
    """The last message decoded on each key, per type, in this process: the other subscriptions on that key
    take it instead of decoding the same bytes again.

    A composed robot's services each subscribe to the robot's odometry, pose, scan, sonar and clock: the
    planner's, the docking service's and the battery's subscriptions decoded each odometry sample three times. As rclcpp hands
    one intra-process message to every subscription as a const pointer, a received message is shared:
    callbacks read it and never change it. Bytes equal to the last on the key decode to an equal message, so
    sharing changes nothing else; a payload that fails validation is never remembered (each subscription
    rejects it itself). Safe from any thread: a race between two decodes costs one decode more.
    """

    def __init__(self) -> None:
        self._last: dict[tuple[type[Message], str], tuple[bytes, Message]] = {}

    def decode(self, msg_type: type[M], key: str, data: bytes) -> M:
        if len(data) > SHARED_DECODE_MAX_BYTES:
            return msg_type.decode(data)
        slot = (msg_type, key)
        last = self._last.get(slot)
        if last is not None and last[0] == data:
            return last[1]  # type: ignore[return-value]
        msg = msg_type.decode(data)
        if len(self._last) >= SHARED_DECODE_MAX_KEYS:
            self._last.clear()
        self._last[slot] = (data, msg)
        return msg


#: This process's shared decodes (every node of a composed process shares it).
SHARED_DECODES = SharedDecodes()


class Subscription(Generic[M]):
    """Receives one message type on one key (wildcards allowed) and hands valid messages to a callback.

    The callback gets the decoded message; with ``with_key=True`` it gets ``(key, message)``; with
    ``with_answered=True`` the message is followed by the sim time of the control tick it answers (from
    its attachment, :func:`~shared.encoding.answered_tick_s`; ``None`` when the publisher did not say). Messages
    reach the callback in arrival order: one runs at once only while none of this subscription's is
    queued, and the queue keeps the last ``qos.depth`` (older ones are dropped and counted).

    With ``undecoded=True`` the callback gets the payload's bytes, type and size checked but not decoded:
    for large messages the subscriber reads only now and then. It decodes them itself when it needs them
    (``msg_type.decode``) and reports one that fails with :meth:`Node.reject`, as the subscription would.
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
        undecoded: bool = False,
        with_answered: bool = False,
    ) -> None:
        self._node = node
        self.msg_type = msg_type
        self.key = topic if absolute else node.key(topic)
        if with_answered:  # the queue carries (message, answered) pairs: the callback gets them spread
            if with_key:
                callback = functools.partial(_spread_after_key, callback)
            else:
                callback = functools.partial(_spread, callback)
        self._callback = callback
        self._with_answered = with_answered
        self._inline = inline
        self._with_key = with_key
        self._queue: deque[tuple[str, M]] = deque(maxlen=max(1, qos.depth))
        self._scheduled = False
        self._lock = threading.Lock()
        self._encoding = encoding_for(msg_type.TYPE_NAME)
        self._decode: Callable[[str, bytes], Any] = (
            _payload_bytes if undecoded else functools.partial(SHARED_DECODES.decode, msg_type)
        )
        self._received = node.stats.received
        self._dropped = node.stats.dropped
        executor = node.executor
        self._try_run_now = executor.try_run_now
        self._run_inline = executor.run_inline
        self._post_drain = executor.post_drain
        #: Without wildcards every sample's key is the subscription's own key: no need to read it back.
        self._exact_key = "" if "*" in self.key else self.key
        self._receiving = True
        #: Shared with the session's other subscriptions on this key (:mod:`shared.subscriber_hub`).
        self._subscriber = SUBSCRIBER_HUB.subscribe(node.session, self.key, self._on_sample)
        try:  # the token after the subscriber: seeing it means the subscription receives
            self._token = node.declare_endpoint("sub", msg_type.TYPE_NAME, self.key)
        except BaseException:  # refused by the service's contract: leave the shared subscriber
            self._receiving = False
            self._subscriber.undeclare()
            raise

    def _on_sample(self, sample: zenoh.Sample) -> None:
        # The hot path of every message: each attribute read of a sample makes a new object, and on a busy
        # machine this code runs with cold caches, so it reads each only once and skips what it can.
        if not self._receiving:  # undeclared while the shared subscriber's thread was handing this one out
            return
        payload = sample.payload
        size = len(payload)
        if not size and sample.kind != _PUT:  # a DELETE (never a message): it has no payload
            return
        key = self._exact_key or str(sample.key_expr)
        try:
            encoding = sample.encoding
            if encoding != self._encoding:  # one comparison in Rust for the common case
                mime, schema = schema_of(encoding)
                if schema and schema != self.msg_type.TYPE_NAME and mime == ENCODING_PREFIX:
                    raise MessageError(f"expected type {self.msg_type.TYPE_NAME}, got {schema}", key=key)
            if size > MAX_PAYLOAD_BYTES:
                raise MessageError(f"payload of {size} bytes exceeds {MAX_PAYLOAD_BYTES}", key=key)
            msg = self._decode(key, payload.to_bytes())
            if self._with_answered:
                msg = (msg, answered_tick_s(sample.attachment))
        except MessageError as exc:
            self._node.reject(key, exc.at(key=key))
            return
        received = self._received
        received[key] = received.get(key, 0) + 1
        if self._inline:
            self._run_inline(self._deliver, key, msg)
            return
        # Run it now unless one of ours is queued (order is kept); the executor declines when it is busy.
        # zenoh-python calls one subscription's callback from one thread, so reading our state needs no lock.
        if not (self._scheduled or self._queue) and (
            self._try_run_now(self._callback, key, msg)
            if self._with_key
            else self._try_run_now(self._callback, msg)
        ):
            return
        with self._lock:
            if len(self._queue) == self._queue.maxlen:
                self._dropped[key] = self._dropped.get(key, 0) + 1
            self._queue.append((key, msg))
            if self._scheduled:
                return
            self._scheduled = True
        self._post_drain(self._next_delivery)

    def _next_delivery(self) -> Work | None:
        """The executor's drain: the oldest queued message's delivery, or ``None`` (and unscheduled) when none."""
        with self._lock:
            if not self._queue:
                self._scheduled = False
                return None
            key, msg = self._queue.popleft()
        return self._deliver, (key, msg)

    def _deliver(self, key: str, msg: M) -> None:
        if self._with_key:
            self._callback(key, msg)
        else:
            self._callback(msg)

    def undeclare(self) -> None:
        """Stop receiving (a subscription a node declares and drops as its needs change)."""
        self._token.undeclare()
        self.close()
        self._node.forget(self, self._token)

    def close(self) -> None:
        """Stop receiving, as the node closes (it undeclares the endpoint tokens itself)."""
        self._receiving = False
        self._subscriber.undeclare()


def _spread(callback: Callable[..., Any], pair: tuple[Any, float | None]) -> Any:
    return callback(*pair)


def _spread_after_key(callback: Callable[..., Any], key: str, pair: tuple[Any, float | None]) -> Any:
    return callback(key, *pair)


class Deferred(Generic[Res]):
    """A service's answer still to come: a handler that must ask other services first (a lifecycle
    manager asks each node it manages) returns one, and calls :meth:`resolve` exactly once, later, on the
    node's executor. The request stays open until then; the client's own timeout bounds the wait."""

    def __init__(self) -> None:
        self._response: Res | None = None
        self._then: Callable[[Res], None] | None = None

    def resolve(self, response: Res) -> None:
        if self._response is not None:
            raise RuntimeError("a deferred answer is given once")
        self._response = response
        if self._then is not None:
            self._then(response)

    def bind(self, then: Callable[[Res], None]) -> None:
        self._then = then
        if self._response is not None:
            then(self._response)


class ServiceServer(Generic[Req, Res]):
    """Answers requests on ``<ns>/<name>`` (a Zenoh queryable); the handler runs on the executor.

    The handler returns a response message (or a :class:`Deferred` one), or raises :class:`ServiceError`
    / ``ValueError`` to reply with an error that names the reason. Malformed requests are rejected before the handler sees them.
    Any other exception is a bug in the handler: the client gets an internal error and the executor
    logs and counts it as a failed callback.
    """

    def __init__(
        self, node: Node, srv: ServiceType[Req, Res], name: str, handler: Callable[[Req], Res | Deferred[Res]]
    ) -> None:
        self._node = node
        self.srv = srv
        self.key = node.key(name)
        self._handler = handler
        self._queryable = node.session.declare_queryable(self.key, self._on_query)
        self._token = node.declare_endpoint("srv", srv.type_name, self.key)

    def _on_query(self, query: zenoh.Query) -> None:
        payload = query.payload
        try:
            request = self.srv.request.decode(payload.to_bytes() if payload is not None else b"\x80")
        except MessageError as exc:
            self._node.reject(self.key, exc.at(key=self.key))
            query.reply_err(str(exc).encode(), encoding=zenoh.Encoding("text/plain"))
            query.drop()
            return
        self._node.post(self._answer, query, request)

    def _answer(self, query: zenoh.Query, request: Req) -> None:
        deferred = False
        try:
            response = self._handler(request)
            if isinstance(response, Deferred):
                deferred = True
                response.bind(lambda result: self._reply_later(query, result))
                return
            self._reply(query, response)
        except (ServiceError, ValueError) as exc:
            query.reply_err(str(exc).encode(), encoding=zenoh.Encoding("text/plain"))
        except Exception as exc:  # a bug in a handler: answer, then let the executor log it; keep serving
            query.reply_err(
                f"internal error: {type(exc).__name__}: {exc}".encode(), encoding=zenoh.Encoding("text/plain")
            )
            raise
        finally:
            if not deferred:
                query.drop()

    def _reply(self, query: zenoh.Query, response: object) -> None:
        if not isinstance(response, self.srv.response):
            raise ServiceError(
                f"handler returned {type(response).__name__}, expected {self.srv.response.__name__}"
            )
        query.reply(self.key, response.encode(), encoding=encoding_for(self.srv.response.TYPE_NAME))

    def _reply_later(self, query: zenoh.Query, response: object) -> None:
        """A deferred answer, given."""
        try:
            self._reply(query, response)
        except ServiceError as exc:
            query.reply_err(str(exc).encode(), encoding=zenoh.Encoding("text/plain"))
        finally:
            query.drop()

    def undeclare(self) -> None:
        self._token.undeclare()
        self._queryable.undeclare()


def decode_reply(srv: ServiceType[Any, Res], key: str, reply: zenoh.Reply) -> Res:
    """The response in a reply, or :class:`ServiceError` naming the key and the server's reason."""
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
    return decode_reply(srv, key, replies[0])
