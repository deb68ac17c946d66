"""zendock's wire contract, written from the outside: what a service needs to take part in a zendock stack.

Only eclipse-zenoh, msgpack and the standard library: nothing of zendock is imported, so a user's own
code can replace any of its services. The examples beside this file (``battery/``, ``docking/``) use it.

The contract, in short:

- A topic, service or action lives at the Zenoh key ``<namespace>/<name>`` (just ``<name>`` without a
  namespace), as zenoh-bridge-ros2dds names them.
- A payload is a msgpack map with the ROS 2 message's field names; nested messages are nested maps,
  arrays are lists, ``builtin_interfaces/Time`` is ``{sec, nanosec}``, NaN is a float NaN. zendock's
  receivers are strict: every field must be there, no other field may be, and a float field wants a number.
- Every sample's encoding is ``application/msgpack;<ROS type name>`` and its attachment is the publisher's
  sequence number (u64 little-endian) followed by its 20-byte id (16-byte session id little-endian, then
  the u32 entity id), so recorders can count losses per publisher.
- A service is a queryable; a malformed request is answered with ``reply_err`` and a reason.
- A node announces itself with the liveliness token ``@zendock/node/<ns>/<node>`` once it is ready (the
  launcher's health check) and each endpoint with ``@zendock/<pub|sub|srv|act>/<ns>/<node>/<type>/<key>``,
  where an empty or slashed chunk is encoded (``/`` -> ``%``, empty -> ``%``); ``zendock nodes`` reads them.
- Actions follow ``<action>/_action/{send_goal,cancel_goal,get_result}`` (queryables) and
  ``<action>/_action/{feedback,status}`` (topics), with action_msgs' layouts (:class:`ActionServer`).
"""

from __future__ import annotations

import argparse
import itertools
import json
import logging
import math
import os
import signal
import struct
import sys
import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import msgpack
import zenoh

ENCODING_PREFIX = "application/msgpack"
GRAPH_PREFIX = "@zendock"
MAX_PAYLOAD_BYTES = 8 * 1024 * 1024
DEFAULT_CONNECT = "tcp/127.0.0.1:7447"
#: action_msgs/GoalStatus values.
ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = 1, 2, 3, 4, 5, 6
TERMINAL = (SUCCEEDED, CANCELED, ABORTED)
Msg = dict[str, Any]


class BadMessage(ValueError):
    """A payload that is not the message it should be: counted and logged, never fatal."""


# --- names ----------------------------------------------------------------------------------------


def topic_key(namespace: str, name: str) -> str:
    namespace, name = namespace.strip("/"), name.strip("/")
    return f"{namespace}/{name}" if namespace else name


def _chunk(text: str) -> str:
    """One token chunk: slashes become ``%`` and an empty chunk is ``%``, so the key splits back."""
    return text.replace("/", "%") if text else "%"


def node_token_key(namespace: str, node: str) -> str:
    return f"{GRAPH_PREFIX}/node/{_chunk(namespace.strip('/'))}/{_chunk(node)}"


def endpoint_token_key(kind: str, namespace: str, node: str, type_name: str, key: str) -> str:
    return f"{GRAPH_PREFIX}/{kind}/{_chunk(namespace.strip('/'))}/{_chunk(node)}/{_chunk(type_name)}/{key}"


def encoding(type_name: str) -> zenoh.Encoding:
    return zenoh.Encoding(f"{ENCODING_PREFIX};{type_name}")


# --- message helpers ------------------------------------------------------------------------------


def time_msg(seconds: float) -> Msg:
    """builtin_interfaces/Time; nanosec stays within [0, 1e9)."""
    whole = math.floor(seconds)
    nanos = int(round((seconds - whole) * 1e9))
    if nanos >= 1_000_000_000:
        whole, nanos = whole + 1, nanos - 1_000_000_000
    return {"sec": int(whole), "nanosec": nanos}


def header(seconds: float, frame_id: str) -> Msg:
    return {"stamp": time_msg(seconds), "frame_id": frame_id}


def pose_msg(x: float, y: float, yaw: float) -> Msg:
    """geometry_msgs/Pose of a planar pose (a rotation about z)."""
    return {"position": {"x": float(x), "y": float(y), "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2.0), "w": math.cos(yaw / 2.0)}}


def planar_pose(pose: Msg) -> tuple[float, float, float]:
    """``(x, y, yaw)`` of a geometry_msgs/Pose map (raises :class:`BadMessage`)."""
    q = [get(pose, f"orientation.{c}", float) for c in "xyzw"]
    yaw = math.atan2(2.0 * (q[3] * q[2] + q[0] * q[1]), 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]))
    return get(pose, "position.x", float), get(pose, "position.y", float), yaw


def twist_msg(linear_x: float, angular_z: float) -> Msg:
    return {"linear": {"x": float(linear_x), "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": float(angular_z)}}


def seconds_of(stamp: Msg) -> float:
    return get(stamp, "sec", int) + get(stamp, "nanosec", int) * 1e-9


def uuid_bytes(value: Any) -> bytes:
    """A unique_identifier_msgs/UUID's 16 bytes (a list of ints on the wire, or bytes)."""
    raw = value.get("uuid") if isinstance(value, dict) else None
    if isinstance(raw, list) and all(isinstance(b, int) and not isinstance(b, bool) and 0 <= b < 256 for b in raw):
        raw = bytes(raw)
    if not isinstance(raw, bytes) or len(raw) != 16:
        raise BadMessage("field 'uuid': expected 16 bytes")
    return raw


def uuid_msg(raw: bytes) -> Msg:
    return {"uuid": list(raw)}


def get(msg: Any, path: str, kind: type, *, finite: bool = True) -> Any:
    """The field at a dotted ``path``, checked to be ``kind`` (a float field also takes an int, as
    zendock's decoders do; ``finite=False`` lets NaN and infinities through)."""
    value = msg
    for part in path.split("."):
        if not isinstance(value, dict) or part not in value:
            raise BadMessage(f"field '{path}': missing")
        value = value[part]
    if kind is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise BadMessage(f"field '{path}': expected a number, got {type(value).__name__}")
        value = float(value)
        if finite and not math.isfinite(value):
            raise BadMessage(f"field '{path}': must be finite, got {value}")
    elif kind is int and (isinstance(value, bool) or not isinstance(value, int)):
        raise BadMessage(f"field '{path}': expected an integer, got {type(value).__name__}")
    elif kind is not int and not isinstance(value, kind):
        raise BadMessage(f"field '{path}': expected {kind.__name__}, got {type(value).__name__}")
    return value


def exact_fields(msg: Msg, names: tuple[str, ...], type_name: str) -> None:
    """A request must have exactly these fields: a misspelt one would otherwise be silently ignored."""
    unknown = sorted(str(k) for k in msg if k not in names)
    if unknown:
        raise BadMessage(f"field '{unknown[0]}': unknown field for {type_name}")
    for name in names:
        if name not in msg:
            raise BadMessage(f"field '{name}': missing")


def unpack(payload: bytes) -> Msg:
    """msgpack bytes -> a map, or :class:`BadMessage`."""
    if len(payload) > MAX_PAYLOAD_BYTES:
        raise BadMessage(f"payload of {len(payload)} bytes exceeds {MAX_PAYLOAD_BYTES}")
    try:
        msg = msgpack.unpackb(payload, raw=False, strict_map_key=True)
    except Exception as exc:  # msgpack raises several unrelated types for garbage
        raise BadMessage(f"payload is not valid msgpack ({type(exc).__name__})") from None
    if not isinstance(msg, dict):
        raise BadMessage(f"expected a map, got {type(msg).__name__}")
    return msg


# --- options --------------------------------------------------------------------------------------


@dataclass
class Options:
    """What the launcher hands a service: ``--namespace``, ``--connect``, ``-p name=value`` (repeated)."""

    node_name: str
    namespace: str = ""
    connect: list[str] = field(default_factory=lambda: [DEFAULT_CONNECT])
    listen: list[str] = field(default_factory=list)
    params: dict[str, Any] = field(default_factory=dict)
    log_level: str = "INFO"


def parse_value(text: str) -> Any:
    """A ``-p`` value: JSON (numbers, lists, ``true``) where it parses, YAML's booleans, else the text."""
    lowered = text.strip().lower()
    if lowered in ("true", "yes", "on", "false", "no", "off"):
        return lowered in ("true", "yes", "on")
    try:
        return json.loads(text)
    except ValueError:
        return text


def parse_options(node_name: str, description: str, argv: list[str] | None = None) -> Options:
    """The flags every zendock service takes; env ``ZENDOCK_CONNECT`` (comma-separated) and
    ``ZENDOCK_NAMESPACE`` are the defaults. Unknown flags are ignored with a warning, so a launcher
    that passes zendock's own service flags (``--config``...) does not stop a replacement from starting."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--namespace", default=os.environ.get("ZENDOCK_NAMESPACE", ""))
    parser.add_argument("--connect", action="append", default=None, metavar="ENDPOINT")
    parser.add_argument("--listen", action="append", default=[], metavar="ENDPOINT")
    parser.add_argument("-p", "--param", action="append", default=[], metavar="NAME=VALUE")
    parser.add_argument("--node-name", default=node_name)
    parser.add_argument("--log-level", default="INFO", type=str.upper)
    args, unknown = parser.parse_known_args(argv)
    env_connect = [e.strip() for e in os.environ.get("ZENDOCK_CONNECT", "").split(",") if e.strip()]
    params: dict[str, Any] = {}
    for text in args.param:
        name, sep, value = text.partition("=")
        if not sep or not name.strip():
            parser.error(f"-p {text!r}: expected NAME=VALUE")
        params[name.strip()] = parse_value(value)
    logging.basicConfig(level=args.log_level, stream=sys.stderr, datefmt="%H:%M:%S",
                        format=f"%(asctime)s %(levelname)s [{args.node_name}] %(message)s")
    if unknown:
        logging.getLogger(args.node_name).warning("ignoring unknown arguments %s", unknown)
    return Options(args.node_name, args.namespace.strip("/"), args.connect or env_connect or [DEFAULT_CONNECT],
                   args.listen, params, args.log_level)


# --- the node -------------------------------------------------------------------------------------


class Publisher:
    """One topic's publisher: msgpack payload, the type in the encoding, sequence number and id attached."""

    def __init__(self, node: Node, topic: str, type_name: str, *, reliable: bool = True, block: bool = False) -> None:
        self.key = node.key(topic)
        self._node = node
        self._pub = node.session.declare_publisher(
            self.key, encoding=encoding(type_name),
            reliability=zenoh.Reliability.RELIABLE if reliable else zenoh.Reliability.BEST_EFFORT,
            congestion_control=zenoh.CongestionControl.BLOCK if block else zenoh.CongestionControl.DROP)
        entity = self._pub.id
        self._gid = int(str(entity.zid), 16).to_bytes(16, "little") + struct.pack("<I", entity.eid)
        self._seq = itertools.count(1)
        self._lock = threading.Lock()
        node.declare_endpoint("pub", type_name, self.key)

    def publish(self, msg: Msg) -> None:
        payload = msgpack.packb(msg, use_bin_type=True)
        with self._lock:  # the put order is the sequence order
            self._pub.put(payload, attachment=struct.pack("<Q", next(self._seq)) + self._gid)
        self._node.count("published", self.key)


class Node:
    """A session, its tokens, and one lock that every callback holds, so service code needs no locks.

    Zenoh calls back on its own threads; each callback here decodes the payload there, then runs the
    service's handler under :attr:`lock`. A payload that fails to decode or that the handler refuses
    (:class:`BadMessage`) is counted and logged (once per key every 5 s); any other exception in a
    handler is logged and counted too: input never kills the node.
    """

    def __init__(self, options: Options) -> None:
        self.name = options.node_name
        self.namespace = options.namespace
        self.params = options.params
        self.log = logging.getLogger(self.name)
        self.lock = threading.RLock()
        self.stopping = threading.Event()
        self.counters: dict[str, dict[str, int]] = {"published": {}, "received": {}, "rejected": {}}
        self.callback_errors = 0
        self._last_warned: dict[str, float] = {}
        self._tokens: list[Any] = []
        self._entities: list[Any] = []
        for sig in (signal.SIGINT, signal.SIGTERM):  # from the start: a stop while connecting still exits 0
            signal.signal(sig, lambda *_: self.stopping.set())
        config = zenoh.Config()
        config.insert_json5("mode", '"client"')
        config.insert_json5("scouting/multicast/enabled", "false")  # explicit endpoints only, as zendock
        config.insert_json5("transport/shared_memory/enabled", "false")
        config.insert_json5("connect/endpoints", json.dumps(options.connect))
        config.insert_json5("listen/endpoints", json.dumps(options.listen))
        config.insert_json5("connect/timeout_ms", "-1")  # keep trying: start order does not matter
        config.insert_json5("connect/exit_on_failure", "false")
        self.log.info("connecting to %s", ",".join(options.connect))
        self.session = self._open(config)
        self.use_sim_time = bool(self.params.get("use_sim_time", False))
        self._sim_now = 0.0
        self.clock_started = False
        self._tick = threading.Event()
        if self.use_sim_time:
            self.subscribe("clock", "rosgraph_msgs/msg/Clock", self._on_clock)

    def _open(self, config: zenoh.Config) -> zenoh.Session:
        """``zenoh.open`` waits for the router (start order does not matter) inside Rust, where no Python
        signal handler runs; so it waits on a helper thread and a stop meanwhile exits at once, with 0."""
        opened: list[zenoh.Session] = []
        opener = threading.Thread(target=lambda: opened.append(zenoh.open(config)), daemon=True)
        opener.start()
        while opener.is_alive():
            opener.join(0.1)
            if self.stopping.is_set():
                self.log.info("stopped before the router answered")
                os._exit(0)  # the opener thread cannot be interrupted; nothing is open yet to close
        if not opened:
            raise RuntimeError("zenoh.open failed (see the error above)")
        return opened[0]

    def key(self, name: str) -> str:
        return topic_key(self.namespace, name)

    def now(self) -> float:
        """Seconds on the node's clock: the simulator's (``use_sim_time``) or the wall's."""
        return self._sim_now if self.use_sim_time else time.time()

    def _on_clock(self, msg: Msg) -> None:
        self._sim_now = seconds_of(get(msg, "clock", dict))
        self.clock_started = True
        self._tick.set()

    # graph

    def declare_endpoint(self, kind: str, type_name: str, key: str) -> Any:
        token = self.session.liveliness().declare_token(endpoint_token_key(kind, self.namespace, self.name, type_name, key))
        self._tokens.append(token)
        return token

    def declare_ready(self) -> None:
        """The node token (healthy for the launcher) and the counters queryable ``zendock bench`` reads."""
        self._tokens.append(self.session.liveliness().declare_token(node_token_key(self.namespace, self.name)))
        stats_key = f"{GRAPH_PREFIX}/stats/{_chunk(self.namespace)}/{_chunk(self.name)}"
        self._entities.append(self.session.declare_queryable(stats_key, self._on_stats))
        self.log.info("ready (namespace %r)", self.namespace)

    def _on_stats(self, query: zenoh.Query) -> None:
        body = {"node": self.name, "namespace": self.namespace, "dropped": {}, "extra": {},
                "callback_errors": self.callback_errors, "now": self.now(),
                **{name: dict(counts) for name, counts in self.counters.items()}}
        query.reply(query.key_expr, json.dumps(body))

    def count(self, counter: str, key: str) -> None:
        counts = self.counters[counter]
        counts[key] = counts.get(key, 0) + 1

    def reject(self, key: str, reason: str) -> None:
        """Count and log (at most every 5 s per key) a payload that is not what ``key`` carries."""
        self.count("rejected", key)
        now = time.monotonic()
        if now - self._last_warned.get(key, -math.inf) >= 5.0:
            self._last_warned[key] = now
            self.log.warning("rejected message on %s (%d so far): %s", key, self.counters["rejected"][key], reason)

    def guarded(self, key: str, handler: Callable[..., Any], *args: Any) -> bool:
        """Run a handler under the node's lock; a refusal or a bug is counted and logged, never raised.
        Returns whether the handler ran to its end."""
        with self.lock:
            try:
                handler(*args)
                return True
            except BadMessage as exc:
                self.reject(key, str(exc))
            except Exception:
                self.callback_errors += 1
                self.log.exception("callback on %s failed (%d so far)", key, self.callback_errors)
        return False

    # endpoints

    def publisher(self, topic: str, type_name: str, *, reliable: bool = True, block: bool = False) -> Publisher:
        return Publisher(self, topic, type_name, reliable=reliable, block=block)

    def subscribe(self, topic: str, type_name: str, callback: Callable[[Msg], Any], *, key: str | None = None) -> Any:
        """Subscribe to ``topic`` (or an absolute ``key``); the callback gets the decoded map. Returns a
        handle whose ``undeclare()`` drops the subscription and its token."""
        full_key = key or self.key(topic)
        expected = encoding(type_name)

        def on_sample(sample: zenoh.Sample) -> None:
            if sample.kind != zenoh.SampleKind.PUT:
                return
            mime, _, schema = str(sample.encoding).partition(";")
            if mime == ENCODING_PREFIX and schema and sample.encoding != expected:
                self.reject(full_key, f"expected type {type_name}, got {schema}")
                return
            try:
                msg = unpack(sample.payload.to_bytes())
            except BadMessage as exc:
                self.reject(full_key, str(exc))
                return
            if self.guarded(full_key, callback, msg):
                self.count("received", full_key)

        subscriber = self.session.declare_subscriber(full_key, on_sample)
        token = self.declare_endpoint("sub", type_name, full_key)
        self._entities.append(subscriber)
        return _Handle(subscriber, token, self)

    def serve(self, name: str, srv_type: str, handler: Callable[[Msg], Msg], *, token: bool = True) -> None:
        """A service on ``<ns>/<name>``: ``handler(request) -> response``; :class:`BadMessage` or ``ValueError``
        from it (or an undecodable request) is answered with ``reply_err`` and the reason."""
        key = self.key(name)

        def on_query(query: zenoh.Query) -> None:
            payload = query.payload.to_bytes() if query.payload is not None else b"\x80"
            try:
                request = unpack(payload)
                with self.lock:
                    response = handler(request)
                query.reply(key, msgpack.packb(response, use_bin_type=True), encoding=encoding(f"{srv_type}_Response"))
            except (BadMessage, ValueError) as exc:
                self.reject(key, str(exc))
                query.reply_err(f"{key}: {srv_type}: {exc}".encode(), encoding=zenoh.Encoding("text/plain"))
            except Exception as exc:  # a bug in the handler: answer, log, keep serving
                self.callback_errors += 1
                self.log.exception("service %s failed", key)
                query.reply_err(f"internal error: {type(exc).__name__}: {exc}".encode(), encoding=zenoh.Encoding("text/plain"))
            finally:
                query.drop()

        self._entities.append(self.session.declare_queryable(key, on_query))
        if token:
            self.declare_endpoint("srv", srv_type, key)

    # running

    def run(self, period_s: float, step: Callable[[], None], on_stop: Callable[[], None] | None = None) -> int:
        """Call ``step`` every ``period_s`` seconds of the node's clock until SIGINT or SIGTERM; then run
        ``on_stop`` (a last word on the bus, such as a zero twist), close the session and return 0 (the
        exit code). Steps run under the node's lock."""
        next_due: float | None = None
        try:
            while not self.stopping.is_set():
                # Short waits: the main thread must come back often to run a signal handler.
                self._tick.wait(0.1 if self.use_sim_time else min(0.1, period_s / 2))
                self._tick.clear()
                if self.use_sim_time and not self.clock_started:
                    continue
                now = self.now()
                if next_due is None or now < next_due - 10 * period_s:  # first step, or the clock went back
                    next_due = now
                if now >= next_due - 1e-6:
                    next_due = max(next_due + period_s, now - period_s)  # never a burst of catch-up steps
                    self.guarded("step", step)
        finally:
            if on_stop is not None:
                self.guarded("stop", on_stop)
            self.close()
        return 0

    def close(self) -> None:
        self.stopping.set()
        for item in [*self._tokens, *self._entities]:
            try:
                item.undeclare()
            except Exception:  # the session may already be closing
                pass
        self.session.close()
        self.log.info("stopped")


class _Handle:
    def __init__(self, subscriber: Any, token: Any, node: Node) -> None:
        self._parts, self._node = [subscriber, token], node

    def undeclare(self) -> None:
        for part in self._parts:
            part.undeclare()
            for owned in (self._node._entities, self._node._tokens):
                if part in owned:
                    owned.remove(part)


# --- actions --------------------------------------------------------------------------------------


@dataclass
class GoalHandle:
    """One accepted goal on the server side."""

    goal_id: bytes
    goal: Msg
    stamp: Msg
    status: int = ACCEPTED
    result: Msg | None = None

    @property
    def active(self) -> bool:
        return self.status not in TERMINAL

    def info(self) -> Msg:
        return {"goal_id": uuid_msg(self.goal_id), "stamp": self.stamp}


class ActionServer:
    """Serves one action with zendock's (and rmw_zenoh's) key layout, one goal at a time.

    ``on_goal(goal)`` checks a goal (raise ``ValueError`` to reject it: the client sees the reason) and
    ``on_accepted(handle)`` starts it; a new goal preempts the active one (it ends CANCELED with
    ``empty_result()``). ``on_cancel(handle)`` is told of a cancel request; it ends the goal itself
    (:meth:`finish` with CANCELED) once the robot is stopped. get_result queries for a running goal are
    held and answered when it ends.
    """

    def __init__(self, node: Node, name: str, action_type: str, *, on_goal: Callable[[Msg], None],
                 on_accepted: Callable[[GoalHandle], None], on_cancel: Callable[[GoalHandle], None],
                 empty_result: Callable[[], Msg]) -> None:
        self.node, self.type = node, action_type
        self._on_goal, self._on_accepted, self._on_cancel, self._empty_result = on_goal, on_accepted, on_cancel, empty_result
        self.active: GoalHandle | None = None
        self._finished: dict[bytes, GoalHandle] = {}
        self._waiting: dict[bytes, list[zenoh.Query]] = {}
        part = f"{name}/_action"
        self._feedback = node.publisher(f"{part}/feedback", f"{action_type}_FeedbackMessage")
        self._status = node.publisher(f"{part}/status", "action_msgs/msg/GoalStatusArray", block=True)
        node.serve(f"{part}/send_goal", f"{action_type}_SendGoal", self._send_goal)
        node.serve(f"{part}/cancel_goal", "action_msgs/srv/CancelGoal", self._cancel_goal)
        self._result_key = node.key(f"{part}/get_result")
        node._entities.append(node.session.declare_queryable(self._result_key, self._get_result))
        node.declare_endpoint("act", action_type, node.key(name))

    def _send_goal(self, request: Msg) -> Msg:
        exact_fields(request, ("goal_id", "goal"), f"{self.type}_SendGoal_Request")
        goal_id, goal = uuid_bytes(request["goal_id"]), get(request, "goal", dict)
        self._on_goal(goal)
        handle = GoalHandle(goal_id, goal, time_msg(self.node.now()))
        if self.active is not None and self.active.active:
            self.finish(self.active, CANCELED, self._empty_result())
        self.active = handle
        self._publish_status()
        self._on_accepted(handle)
        return {"accepted": True, "stamp": handle.stamp}

    def _cancel_goal(self, request: Msg) -> Msg:
        exact_fields(request, ("goal_info",), "action_msgs/srv/CancelGoal_Request")
        wanted = uuid_bytes(get(request, "goal_info.goal_id", dict))
        goal = self.active
        if goal is None or not goal.active:
            return {"return_code": 3 if goal else 2, "goals_canceling": []}  # terminated / unknown goal
        if any(wanted) and wanted != goal.goal_id:  # the zero id means "every goal"
            return {"return_code": 3 if wanted in self._finished else 2, "goals_canceling": []}
        self.set_status(goal, CANCELING)
        self._on_cancel(goal)
        return {"return_code": 0, "goals_canceling": [goal.info()]}

    def _get_result(self, query: zenoh.Query) -> None:
        try:
            request = unpack(query.payload.to_bytes() if query.payload is not None else b"\x80")
            exact_fields(request, ("goal_id",), f"{self.type}_GetResult_Request")
            goal_id = uuid_bytes(request["goal_id"])
        except BadMessage as exc:
            self.node.reject(self._result_key, str(exc))
            query.reply_err(str(exc).encode(), encoding=zenoh.Encoding("text/plain"))
            query.drop()
            return
        with self.node.lock:
            done = self._finished.get(goal_id)
            if done is not None:
                self._reply_result(query, done)
            elif self.active is not None and self.active.goal_id == goal_id:
                self._waiting.setdefault(goal_id, []).append(query)
            else:
                query.reply_err(f"unknown goal {goal_id.hex()}".encode(), encoding=zenoh.Encoding("text/plain"))
                query.drop()

    def _reply_result(self, query: zenoh.Query, handle: GoalHandle) -> None:
        response = {"status": handle.status, "result": handle.result}
        try:
            query.reply(self._result_key, msgpack.packb(response, use_bin_type=True),
                        encoding=encoding(f"{self.type}_GetResult_Response"))
        finally:
            query.drop()

    def set_status(self, handle: GoalHandle, status: int) -> None:
        handle.status = status
        self._publish_status()

    def publish_feedback(self, handle: GoalHandle, feedback: Msg) -> None:
        if handle.active:
            self._feedback.publish({"goal_id": uuid_msg(handle.goal_id), "feedback": feedback})

    def finish(self, handle: GoalHandle, status: int, result: Msg) -> None:
        """End a goal (SUCCEEDED, CANCELED or ABORTED) and answer everyone waiting for its result."""
        if not handle.active:
            return
        handle.status, handle.result = status, result
        self._finished[handle.goal_id] = handle
        while len(self._finished) > 64:
            self._finished.pop(next(iter(self._finished)))
        self._publish_status()
        for query in self._waiting.pop(handle.goal_id, []):
            self._reply_result(query, handle)

    def _publish_status(self) -> None:
        handles = list(self._finished.values())[-8:]
        if self.active is not None and self.active.active:
            handles.append(self.active)
        self._status.publish({"status_list": [{"goal_info": h.info(), "status": h.status} for h in handles]})

    def close(self) -> None:
        for queries in self._waiting.values():
            for query in queries:
                query.reply_err(b"action server shutting down", encoding=zenoh.Encoding("text/plain"))
                query.drop()
        self._waiting.clear()


class ActionClient:
    """Sends goals to another service's action server without blocking: ``on_done(status, result, error)``
    runs under the node's lock when the goal ends (``status`` 0 when it was rejected or failed)."""

    def __init__(self, node: Node, name: str, action_type: str) -> None:
        self.node, self.type, self._part = node, action_type, f"{name}/_action"

    def _get(self, part: str, request: Msg, type_name: str, timeout_s: float,
             on_answer: Callable[[Msg | None, str], None]) -> None:
        replies: list[zenoh.Reply] = []

        def finished() -> None:
            answer, error = None, f"no answer from {self.node.key(self._part)}/{part} in {timeout_s:g} s"
            if replies and replies[0].ok is not None:
                try:
                    answer, error = unpack(replies[0].ok.payload.to_bytes()), ""
                except BadMessage as exc:
                    error = f"malformed answer: {exc}"
            elif replies and replies[0].err is not None:
                error = replies[0].err.payload.to_string()
            self.node.guarded(f"{self._part}/{part}", on_answer, answer, error)

        self.node.session.get(self.node.key(f"{self._part}/{part}"), zenoh.handlers.Callback(replies.append, finished),
                              payload=msgpack.packb(request, use_bin_type=True), encoding=encoding(type_name),
                              timeout=timeout_s, target=zenoh.QueryTarget.BEST_MATCHING)

    def send_goal(self, goal: Msg, on_done: Callable[[int, Msg | None, str], None]) -> bytes:
        goal_id = uuid.uuid4().bytes

        def accepted(answer: Msg | None, error: str) -> None:
            if answer is None or answer.get("accepted") is not True:
                on_done(0, None, error or "goal rejected")
                return
            self._get("get_result", {"goal_id": uuid_msg(goal_id)}, f"{self.type}_GetResult_Request", 3600.0,
                      lambda result, err: on_done(get(result, "status", int), get(result, "result", dict), "")
                      if result is not None else on_done(0, None, err))

        self._get("send_goal", {"goal_id": uuid_msg(goal_id), "goal": goal}, f"{self.type}_SendGoal_Request", 5.0,
                  accepted)
        return goal_id

    def cancel_goal(self, goal_id: bytes) -> None:
        request = {"goal_info": {"goal_id": uuid_msg(goal_id), "stamp": time_msg(0.0)}}
        self._get("cancel_goal", request, "action_msgs/srv/CancelGoal_Request", 5.0, lambda _a, _e: None)
