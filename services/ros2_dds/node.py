"""The ROS 2 DDS face: zendock as real rclpy nodes on ROS 2's default middleware (Jazzy, Fast DDS).

``services.ros2_bridge`` speaks rmw_zenoh's wire on zendock's router; most ROS 2 machines run Fast DDS,
so this service is the same face built on rclpy itself (run it from ``.venv-ros2``, see ``make ros2``).
It reads the same tables (:mod:`shared.ros2.bridge_routes`) and, on ``domain_id`` with discovery on
loopback only (``discovery_range``):

* shows one rclpy node per zendock service (``simulator``, ``battery``, ``pose``, ``planner``,
  ``perception``, ``docking``) while that service's zendock node token is up, and its own ``ros2_dds``;
* zendock -> ROS 2: each topic with its Jazzy type and QoS, read from zendock and published only while a
  ROS 2 subscription matches the publisher (polled every ``demand_poll_s``); transient-local topics
  (``/map``, ``/tf_static``) are always read, published TRANSIENT_LOCAL, and the last one is published
  again when its node comes back, so a late subscriber gets it;
* ROS 2 -> zendock: ``/cmd_vel`` (Twist, or TwistStamped while ROS 2 nodes publish it so; while both are
  published at once, TwistStamped on a second DDS participant's node ``simulator_twist_stamped``: one
  participant cannot have a topic under two types), ``/goal_pose`` (a ``navigate_to_pose`` goal), ``/initialpose``
  (``simulator/set_localisation``);
* ``navigate_to_pose``, ``dock_robot``, ``undock_robot``: rclpy ActionServers relaying goal, feedback,
  result and cancel to zendock's action servers (:class:`shared.action.ActionClient`); zendock's server
  decides acceptance, and is the only authority on a goal;
* Nav2's lifecycle, costmap and map services (:data:`shared.ros2.bridge_routes.SERVICES`), relayed;
* each node's parameters are its zendock service's (``ros2 param``; :mod:`.parameters`).

Each of the face's few hundred readers and writers starts with one sample of history, not Fast DDS's
hundred (``fastdds_profiles.xml``, unless ``FASTRTPS_DEFAULT_PROFILES_FILE`` names another file).

Messages convert by field name (:mod:`.convert`). Anything that does not convert is refused, counted and
logged at most once per interval per kind; nothing from ROS 2 stops the face.

Threads: zendock's executor (the main thread) owns the zendock side and the rclpy nodes' lifecycle; an
rclpy MultiThreadedExecutor spins on its own thread and hands what ROS 2 sends to zendock's executor
(``node.post``). Action execute callbacks wait on their zendock goal in the rclpy executor's threads.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

import msgspec
import zenoh
from msgspec import Meta

from services.ros2_dds.convert import ConversionError, from_ros, ros_class, to_ros
from services.ros2_dds.lazy_interfaces import load_interfaces_on_use, load_on_first_use
from shared import topics
from shared.action import ActionClient, ClientGoal
from shared.interface_types import GoalStatusCode
from shared.interfaces.navigation import NavigateToPoseGoal
from shared.messages import PoseStamped
from shared.names import node_token_key, parse_token_key
from shared.node import SENSOR_DATA, Node, QoS, ServiceError, Subscription, call_service
from shared.parameters import ServiceParams
from shared.ratelimit import RateLimitedLogger
from shared.ros2.bridge_routes import (
    ACTIONS,
    INBOUND,
    SERVICES,
    TOPICS,
    TWIST_STAMPED,
    BridgedAction,
    BridgedService,
    Inbound,
    Route,
    default_domain_id,
)
from shared.ros2.commands import RosCommands
from shared.ros2.wire import Durability, QosProfile, Reliability
from shared.runtime import ServiceSpec

STATS_PERIOD_S = 30.0
#: Fast DDS defaults for the face's readers and writers (see the file), unless the user names their own.
FAST_DDS_PROFILES = Path(__file__).with_name("fastdds_profiles.xml")
FACE_NODE = "ros2_dds"
#: How long a ROS 2 goal waits for zendock's server to accept or reject it.
ACCEPT_WAIT_S = 10.0
EXECUTOR_THREADS = 8
#: rclpy's parameter that starts a node's ``~/get_type_description`` service (true unless overridden).
START_TYPE_DESCRIPTION_SERVICE = "start_type_description_service"
#: The zendock services shown as ROS 2 nodes (every owner in the tables).
OWNERS: tuple[str, ...] = tuple(
    dict.fromkeys(
        [r.owner for r in TOPICS]
        + [i.owner for i in INBOUND]
        + [a.owner for a in ACTIONS]
        + [s.owner for s in SERVICES]
    )
)


#: rosidl_generator_py's code generator, which its ``__init__`` imports beside ``import_type_support``.
ROSIDL_GENERATOR = "rosidl_generator_py.generate_py_impl"


def keep_rosidl_generator_out() -> bool:
    """Spare the face rosidl's code generator; call it before the first rclpy or message import.

    Every generated message class imports ``rosidl_generator_py`` for ``import_type_support``, and that
    package's ``__init__`` also imports ``generate_py`` (the build-time generator: rosidl_parser with lark,
    empy, rosidl_pycommon; 45 modules, 3 MB of the face's RSS idle and busy in ``zendock bench nav2``)
    unless that import fails, which it allows for: it logs at debug and goes on. Nothing at run time
    generates code. True when it took effect: False once ``rosidl_generator_py`` has been imported.
    """
    if "rosidl_generator_py" in sys.modules:
        return sys.modules.get(ROSIDL_GENERATOR, False) is None
    sys.modules[ROSIDL_GENERATOR] = None  # type: ignore[assignment]  # its import raises ImportError
    return True


class Params(ServiceParams):
    """Parameters of ``python -m services.ros2_dds``."""

    domain_id: Annotated[
        int, Meta(ge=0, le=232, description="ROS 2 domain (default: ROS_DOMAIN_ID, else 0)")
    ] = msgspec.field(default_factory=default_domain_id)
    discovery_range: Annotated[
        Literal["LOCALHOST", "SUBNET", "OFF", "SYSTEM_DEFAULT"],
        Meta(description="ROS_AUTOMATIC_DISCOVERY_RANGE of the rclpy context (default: loopback only)"),
    ] = "LOCALHOST"
    demand_poll_s: Annotated[
        float,
        Meta(gt=0.0, le=5.0, description="how often the ROS 2 subscription count of each topic is read"),
    ] = 0.2


def rclpy_qos(profile: QosProfile) -> Any:
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy  # noqa: PLC0415

    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=profile.depth,
        reliability=(
            ReliabilityPolicy.BEST_EFFORT
            if profile.reliability is Reliability.BEST_EFFORT
            else ReliabilityPolicy.RELIABLE
        ),
        durability=(
            DurabilityPolicy.TRANSIENT_LOCAL
            if profile.durability is Durability.TRANSIENT_LOCAL
            else DurabilityPolicy.VOLATILE
        ),
    )


@dataclass
class _Outlet:
    """One zendock -> ROS 2 topic: its zendock feed (while wanted) and, while its node is up, its publisher."""

    route: Route
    ros_class: Any
    publisher: Any = None
    feed: Subscription[Any] | None = None
    last: Any = None  # transient-local topics: the last message, for a publisher that comes back


@dataclass
class _Relay:
    """One ROS 2 goal relayed to zendock's server."""

    action: BridgedAction
    zendock_goal: ClientGoal[Any, Any] | None = None
    ros_handle: Any = None
    pending_feedback: Any = None
    done: threading.Event = field(default_factory=threading.Event)
    lock: threading.Lock = field(default_factory=threading.Lock)


@dataclass
class _Face:
    """One zendock service's rclpy node and what hangs on it."""

    owner: str
    node: Any
    action_servers: list[Any] = field(default_factory=list)
    services: list[Any] = field(default_factory=list)
    group: Any = None  # the callback group of its node's servers and subscriptions
    #: ROS 2 -> zendock topics on its node: topic -> (the type it is taken under, the subscription, or None
    #: until it can be made again after a swap of type)
    inlets: dict[str, tuple[Inbound, Any]] = field(default_factory=dict)
    #: nodes of the second participant, each taking one topic under a second type: (topic, type) -> node
    extra: dict[tuple[str, str], Any] = field(default_factory=dict)


class Ros2Dds:
    def __init__(self, node: Node, params: Params) -> None:
        self.node = node
        self.params = params
        self.counts: Counter[str] = Counter()
        self._counts_lock = threading.Lock()
        self._say = RateLimitedLogger(node.log, interval_s=5.0)
        self._lock = threading.RLock()  # rclpy entities of the faces: created, used and destroyed under it
        self._closing = False

        # --- rclpy: a context (one DDS participant); a second one takes /cmd_vel under a second type if asked
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = params.discovery_range
        os.environ.setdefault("FASTRTPS_DEFAULT_PROFILES_FILE", str(FAST_DDS_PROFILES))
        os.environ.pop("ROS_LOCALHOST_ONLY", None)  # deprecated in Jazzy: it would only warn
        keep_rosidl_generator_out()
        load_interfaces_on_use()
        load_on_first_use("yaml")  # rclpy.parameter's, for parameter strings and files
        import rclpy  # noqa: PLC0415 - only in .venv-ros2; imported when the service starts
        from rclpy.executors import MultiThreadedExecutor  # noqa: PLC0415
        from rclpy.signals import SignalHandlerOptions  # noqa: PLC0415

        self._rclpy = rclpy
        self._executor_class = MultiThreadedExecutor
        self._signal_options = SignalHandlerOptions.NO
        self.contexts: list[Any] = []
        self.executors: list[Any] = []
        self._threads: list[threading.Thread] = []
        self._participant(EXECUTOR_THREADS)
        self._own = self._create_node(FACE_NODE, self.contexts[0])
        self.executors[0].add_node(self._own)

        # --- zendock side
        self._commands = RosCommands(node, self._refuse, self._navigate)
        #: zendock's action clients, each made when its action is first used: a client subscribes to its
        #: action's feedback and status, a thread of zenoh-python's apiece, and most of the actions a face
        #: offers are never asked for (measurement 111).
        self._clients: dict[str, ActionClient[Any, Any, Any]] = {}
        self._clients_lock = threading.Lock()
        self.outlets = [_Outlet(route, ros_class(route.ros_type)) for route in TOPICS]
        for outlet in self.outlets:
            if outlet.route.latched:
                self._feed(outlet)
        self.faces: dict[str, _Face] = {}
        self._relays: dict[int, _Relay] = {}  # id(ROS goal message) -> relay, until execute takes it
        self._active: list[_Relay] = []
        self._services_watch = node.session.liveliness().declare_subscriber(
            node_token_key(node.namespace, "*"), self._on_service_token, history=True
        )
        node.create_timer(params.demand_poll_s, self._poll_demand, wall=True)
        node.create_timer(STATS_PERIOD_S, self._report_stats, wall=True)
        node.log.info(
            "ROS 2 domain %d (rclpy, %s, discovery %s): %d topics out, %d in, %d actions",
            params.domain_id,
            os.environ.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp"),
            params.discovery_range,
            len(TOPICS),
            len(INBOUND),
            len(ACTIONS),
        )

    def client(self, action_name: str) -> ActionClient[Any, Any, Any]:
        """zendock's client of ``action_name``, made on first use (any thread may ask)."""
        with self._clients_lock:
            client = self._clients.get(action_name)
            if client is None:
                action = next(a for a in ACTIONS if a.name == action_name)
                client = self._clients[action_name] = ActionClient(self.node, action.zendock, action.name)
            return client

    def _participant(self, threads: int) -> int:
        """A new rclpy context (a DDS participant) with its executor spinning on a thread; its index."""
        context = self._rclpy.Context()
        self._rclpy.init(
            context=context, domain_id=self.params.domain_id, signal_handler_options=self._signal_options
        )
        executor = self._executor_class(num_threads=threads, context=context)
        thread = threading.Thread(
            target=self._spin, args=(executor,), daemon=True, name=f"rclpy-executor-{len(self.contexts)}"
        )
        self.contexts.append(context)
        self.executors.append(executor)
        self._threads.append(thread)
        thread.start()
        return len(self.contexts) - 1

    def _create_node(self, name: str, context: Any, **options: Any) -> Any:
        """An rclpy node of the face, without what rclpy adds to every node that the face has no use for.

        No ``/rosout`` publisher: the face logs through zendock, never through rclpy's logger. No
        ``~/get_type_description`` service: it answers with a topic's type description, which no ROS 2 tool
        of Jazzy asks for (the types and their hashes travel in discovery). They were 21 of the face's DDS
        endpoints (a writer, and a reader and a writer, on each of its seven nodes)."""
        from rclpy.parameter import Parameter  # noqa: PLC0415

        no_type_description = Parameter(START_TYPE_DESCRIPTION_SERVICE, value=False)
        return self._rclpy.create_node(
            name, context=context, enable_rosout=False, parameter_overrides=[no_type_description], **options
        )

    def _spin(self, executor: Any) -> None:
        """rclpy's executor re-raises a callback's exception from ``spin()``: log it and spin on, so one bad
        callback never leaves the face announced but deaf (shutdown races end it with rclpy errors too)."""
        while not self._closing:
            try:
                executor.spin()
                return
            except Exception as exc:
                if self._closing:
                    return
                self._say.warning(
                    "rclpy-callback",
                    "an rclpy callback failed (spinning on): %s: %s",
                    type(exc).__name__,
                    exc,
                )

    # --- the graph: a node per zendock service that is up --------------------------------------------

    def _on_service_token(self, sample: zenoh.Sample) -> None:
        entry = parse_token_key(str(sample.key_expr))
        if entry is not None and entry.node in OWNERS:
            self.node.post(self._service_changed, entry.node, sample.kind == zenoh.SampleKind.PUT)

    def _service_changed(self, owner: str, alive: bool) -> None:
        if self._closing:
            return
        if alive and owner not in self.faces:
            self._open_face(owner)
            self.node.log.info("zendock's %s is up: ROS 2 sees node /%s", owner, owner)
        elif not alive and owner in self.faces:
            self._close_face(self.faces.pop(owner))
            self.node.log.info("zendock's %s is gone: its ROS 2 node is destroyed", owner)

    def _open_face(self, owner: str) -> None:
        from rclpy.action import ActionServer, CancelResponse, GoalResponse  # noqa: PLC0415
        from rclpy.callback_groups import ReentrantCallbackGroup  # noqa: PLC0415

        from services.ros2_dds.parameters import ParameterRelay  # noqa: PLC0415 - rcl_interfaces: .venv-ros2

        with self._lock:
            # Its parameters are the zendock service's (ParameterRelay), not rclpy's own.
            rnode = self._create_node(owner, self.contexts[0], start_parameter_services=False)
            face = _Face(owner, rnode)
            group = ReentrantCallbackGroup()
            face.services.extend(ParameterRelay(self.node, rnode, owner, group).services)
            for outlet in self.outlets:
                if outlet.route.owner == owner:
                    outlet.publisher = rnode.create_publisher(
                        outlet.ros_class, outlet.route.ros_topic, rclpy_qos(outlet.route.qos)
                    )
                    if outlet.last is not None:
                        outlet.publisher.publish(outlet.last)
            face.group = group
            for inbound in INBOUND:  # a topic's first type; _poll_inlet_types follows what ROS 2 publishes
                if inbound.owner == owner and inbound.ros_topic not in face.inlets:
                    face.inlets[inbound.ros_topic] = (inbound, self._subscribe(rnode, inbound, group))
            for action in ACTIONS:
                if action.owner != owner:
                    continue
                face.action_servers.append(
                    ActionServer(
                        rnode,
                        ros_class(action.ros_type),
                        action.name,
                        execute_callback=lambda handle, a=action: self._execute(a, handle),
                        goal_callback=lambda goal, a=action: (
                            GoalResponse.ACCEPT if self._accept(a, goal) else GoalResponse.REJECT
                        ),
                        cancel_callback=lambda handle, a=action: (
                            CancelResponse.ACCEPT if self._cancel(a, handle) else CancelResponse.REJECT
                        ),
                        callback_group=group,
                    )
                )
            for service in SERVICES:
                if service.owner == owner:
                    face.services.append(
                        rnode.create_service(
                            ros_class(service.ros_type),
                            service.name,
                            lambda request, response, s=service: self._serve(s, request, response),
                            callback_group=group,
                        )
                    )
            self.executors[0].add_node(rnode)
            self.faces[owner] = face

    def _close_face(self, face: _Face) -> None:
        for relay in list(self._active):
            if relay.action.owner == face.owner:
                relay.done.set()  # its server went with the service: the execute callback aborts the goal
        with self._lock:
            for outlet in self.outlets:
                if outlet.route.owner == face.owner:
                    outlet.publisher = None
                    if outlet.feed is not None and not outlet.route.latched:
                        outlet.feed.undeclare()
                        outlet.feed = None
            for server in face.action_servers:
                server.destroy()
            for served in face.services:
                face.node.destroy_service(served)
            for executor, rnode in [
                (self.executors[0], face.node),
                *((self.executors[-1], e) for e in face.extra.values()),
            ]:
                executor.remove_node(rnode)
                rnode.destroy_node()

    # --- zendock -> ROS 2 ----------------------------------------------------------------------------

    def _poll_demand(self) -> None:
        self._poll_inlet_types()
        with self._lock:
            for outlet in self.outlets:
                if outlet.route.latched:
                    continue
                wanted = outlet.publisher is not None and outlet.publisher.get_subscription_count() > 0
                if wanted and outlet.feed is None:
                    self._feed(outlet)
                    self.node.log.info(
                        "a ROS 2 node subscribes to /%s: forwarding %s",
                        outlet.route.ros_topic,
                        self.node.key(outlet.route.zendock_topic),
                    )
                elif not wanted and outlet.feed is not None:
                    outlet.feed.undeclare()
                    outlet.feed = None
                    self.node.log.info(
                        "no ROS 2 subscription to /%s left: no longer forwarding it", outlet.route.ros_topic
                    )

    def _poll_inlet_types(self) -> None:
        """A topic ROS 2 publishes under more than one type (/cmd_vel: Twist, or TwistStamped as Jazzy's
        controllers send it) is taken under whichever its publishers use.

        One DDS participant cannot have a topic under two types. So the face's node holds the topic under one
        type and swaps to the type the publishers use, and back to the first (Jazzy's default) once none is
        left; only while both types are published at once does a second participant (made the first time it
        is needed, a participant costs some 4.5 MB) take the other, on a node ``<owner>_<type>`` that goes
        once the two are not both published."""
        for face in list(self.faces.values()):
            for topic, (held, subscription) in list(face.inlets.items()):
                choices = [i for i in INBOUND if i.ros_topic == topic and i.owner == face.owner]
                if len(choices) < 2:
                    continue
                with self._lock:
                    if self.faces.get(face.owner) is not face:
                        continue
                    if subscription is None and not self._resubscribe(face, topic, held):
                        continue
                    published = {
                        info.topic_type for info in face.node.get_publishers_info_by_topic(f"/{topic}")
                    }
                    wanted = [i for i in choices if i.ros_type in published]
                    if held.ros_type not in published:
                        chosen = wanted[0] if wanted else choices[0]
                        if chosen is not held:
                            self._swap_inlet(face, topic, chosen)
                        held, subscription = face.inlets[topic]
                        if subscription is None:
                            continue
                    for key in [k for k in face.extra if k[0] == topic]:
                        if key[1] == held.ros_type or key[1] not in published:  # a duplicate, or unused
                            self._drop_second_participant_inlet(face, key)
                    for inbound in wanted:
                        if inbound is not held and (topic, inbound.ros_type) not in face.extra:
                            self._second_participant_inlet(face, inbound)

    def _swap_inlet(self, face: _Face, topic: str, inbound: Inbound) -> None:
        """The face's node takes ``topic`` under ``inbound``'s type instead (under ``self._lock``).

        rclpy destroys a subscription once its executor no longer waits on it, and until then the topic keeps
        its old type in the participant: the new subscription is made now if it can be, else at a later poll."""
        _, subscription = face.inlets[topic]
        face.node.destroy_subscription(subscription)
        face.inlets[topic] = (inbound, None)
        self._resubscribe(face, topic, inbound)

    def _resubscribe(self, face: _Face, topic: str, inbound: Inbound) -> bool:
        try:
            face.inlets[topic] = (inbound, self._subscribe(face.node, inbound, face.group))
        except Exception:  # rclpy's RCLError: the old type's topic is not gone yet
            return False
        self.node.log.info("ROS 2 publishes /%s as %s: taking it so", topic, inbound.ros_type)
        return True

    def _second_participant_inlet(self, face: _Face, inbound: Inbound) -> None:
        """``inbound`` on a node of the second participant, while the face's node holds its topic's other type."""
        if len(self.contexts) < 2:
            self._participant(2)
        short = inbound.ros_type.rsplit("/", 1)[-1]
        snake = "".join(f"_{c.lower()}" if c.isupper() else c for c in short).lstrip("_")
        extra = self._create_node(f"{face.owner}_{snake}", self.contexts[1])
        self._subscribe(extra, inbound, None)
        face.extra[(inbound.ros_topic, inbound.ros_type)] = extra
        self.executors[1].add_node(extra)
        self.node.log.info(
            "ROS 2 publishes /%s as %s too: taking that on a second participant's node /%s",
            inbound.ros_topic,
            inbound.ros_type,
            extra.get_name(),
        )

    def _drop_second_participant_inlet(self, face: _Face, key: tuple[str, str]) -> None:
        """The second participant's node for ``key`` (topic, type) goes: no ROS 2 node publishes that type
        any more, or the face's own node now takes it (two would hand each message on twice). The participant
        itself stays, ready for the next time."""
        extra = face.extra.pop(key)
        name = extra.get_name()
        self.executors[-1].remove_node(extra)
        extra.destroy_node()
        self.node.log.info(
            "the second participant's node /%s is gone: ROS 2 publishes /%s under one type again",
            name,
            key[0],
        )

    def _subscribe(self, rnode: Any, inbound: Inbound, group: Any) -> Any:
        return rnode.create_subscription(
            ros_class(inbound.ros_type),
            inbound.ros_topic,
            self._inlet(inbound),
            rclpy_qos(QosProfile()),
            callback_group=group,
        )

    def _feed(self, outlet: _Outlet) -> None:
        qos = SENSOR_DATA if outlet.route.qos.reliability is Reliability.BEST_EFFORT else QoS(depth=10)
        outlet.feed = self.node.create_subscription(
            outlet.route.zendock_type, outlet.route.zendock_topic, lambda msg: self._forward(outlet, msg), qos
        )

    def _forward(self, outlet: _Outlet, msg: Any) -> None:
        try:
            ros_msg = to_ros(msg, outlet.ros_class)
        except ConversionError as exc:
            self._refuse(
                f"encode-{outlet.route.ros_topic}",
                "could not put /%s on ROS 2: %s",
                outlet.route.ros_topic,
                exc,
            )
            return
        with self._lock:
            if outlet.route.latched:
                outlet.last = ros_msg
            if outlet.publisher is None:
                return
            try:
                outlet.publisher.publish(ros_msg)
            except (
                Exception
            ) as exc:  # rclpy's C conversion of a value convert did not catch: refused, not fatal
                self._refuse(
                    f"publish-{outlet.route.ros_topic}",
                    "could not publish /%s: %s",
                    outlet.route.ros_topic,
                    exc,
                )
                return
        self._count(f"out /{outlet.route.ros_topic}")

    # --- ROS 2 -> zendock ----------------------------------------------------------------------------

    def _inlet(self, inbound: Inbound) -> Callable[[Any], None]:
        def on_message(ros_msg: Any) -> None:  # rclpy's thread: the work is zendock's executor's
            self.node.post(self._receive, inbound, ros_msg)

        return on_message

    def _receive(self, inbound: Inbound, ros_msg: Any) -> None:
        topic = f"/{inbound.ros_topic}"
        try:
            if inbound.ros_type == TWIST_STAMPED:
                ros_msg = ros_msg.twist
            msg = from_ros(ros_msg, inbound.zendock_type)
        except ConversionError as exc:
            self._refuse(f"malformed-{inbound.ros_topic}", "refused a message on %s: %s", topic, exc)
            return
        self._count(f"in {topic}")
        self._commands.handle(inbound.ros_topic, msg)

    def _serve(self, service: BridgedService, ros_request: Any, ros_response: Any) -> Any:
        """rclpy's service callback (an executor thread): zendock's service answers, within the service's wait_s;
        without an answer ROS 2 gets the response's defaults (a GetState's ``unknown``) and a log line."""
        where = f"/{service.name}"
        try:
            request = from_ros(ros_request, service.zendock.request)
        except ConversionError as exc:
            self._refuse(f"malformed-{service.name}", "refused a request on %s: %s", where, exc)
            return ros_response
        try:
            reply = call_service(
                self.node.session, self.node.key(service.name), service.zendock, request, service.wait_s
            )
            answer = to_ros(reply, type(ros_response))
        except (ServiceError, ConversionError) as exc:
            self._say.warning(
                f"service-{service.name}", "%s: zendock's service did not answer: %s", where, exc
            )
            return to_ros(service.unanswered(), type(ros_response)) if service.unanswered else ros_response
        self._count(f"service {where}")
        return answer

    def _navigate(self, goal: PoseStamped) -> None:
        self.client(topics.NAVIGATE_TO_POSE).send_goal(NavigateToPoseGoal(pose=goal))

    # --- actions: rclpy ActionServers relaying to zendock's ------------------------------------------

    def _accept(self, action: BridgedAction, ros_goal: Any) -> bool:
        """rclpy's goal callback (an executor thread): zendock's server decides, within ACCEPT_WAIT_S."""
        try:
            goal = from_ros(ros_goal, action.zendock.goal)
        except ConversionError as exc:
            self._refuse(f"goal-{action.name}", "refused a %s goal: %s", action.name, exc)
            return False
        relay = _Relay(action)
        client = self.client(action.name)
        sent = threading.Event()

        def send() -> None:
            relay.zendock_goal = client.send_goal(
                goal,
                on_feedback=lambda fb: self._feedback(relay, fb),
                on_done=lambda _h: relay.done.set(),
                timeout_s=ACCEPT_WAIT_S,
            )
            sent.set()

        self.node.post(send)
        deadline = time.monotonic() + ACCEPT_WAIT_S
        while time.monotonic() < deadline and not self._closing:
            if sent.is_set():
                assert relay.zendock_goal is not None
                with client.lock:
                    accepted = relay.zendock_goal.accepted
                    why = relay.zendock_goal.rejection
                if accepted is not None:
                    break
            time.sleep(0.002)
        else:
            self._refuse(
                f"goal-timeout-{action.name}",
                "%s: zendock's server did not answer a goal in %.0f s",
                action.name,
                ACCEPT_WAIT_S,
            )
            return False
        if not accepted:
            self._refuse(f"goal-rejected-{action.name}", "%s: goal rejected: %s", action.name, why)
            return False
        self._count(f"goal {action.name}")
        with self._lock:
            self._relays[id(ros_goal)] = relay
            self._active.append(relay)
        return True

    def _feedback(self, relay: _Relay, feedback: Any) -> None:
        try:
            ros_feedback = to_ros(feedback, ros_class(f"{relay.action.ros_type}_Feedback"))
        except ConversionError as exc:
            self._refuse(
                f"feedback-{relay.action.name}",
                "could not put %s feedback on ROS 2: %s",
                relay.action.name,
                exc,
            )
            return
        with relay.lock:
            if relay.ros_handle is None:
                relay.pending_feedback = ros_feedback
                return
            handle = relay.ros_handle
        try:
            handle.publish_feedback(ros_feedback)
        except Exception as exc:  # the goal ended meanwhile, or rclpy's C conversion refused a value
            self._refuse(
                f"feedback-publish-{relay.action.name}",
                "could not publish %s feedback: %s",
                relay.action.name,
                exc,
            )
            return
        self._count(f"feedback {relay.action.name}")

    def _cancel(self, action: BridgedAction, ros_handle: Any) -> bool:
        relay = next((r for r in list(self._active) if r.ros_handle is ros_handle), None)
        if relay is None or relay.zendock_goal is None:
            return False
        self.node.post(self.client(action.name).cancel_goal, relay.zendock_goal)
        self._count(f"cancel {action.name}")
        return True

    def _execute(self, action: BridgedAction, ros_handle: Any) -> Any:
        """rclpy's execute callback (an executor thread): waits for zendock's goal to end, then ends the ROS 2
        goal the same way with zendock's result."""
        result_class = ros_class(f"{action.ros_type}_Result")
        with self._lock:
            relay = self._relays.pop(id(ros_handle.request), None)
        if relay is None or relay.zendock_goal is None:
            ros_handle.abort()
            return result_class()
        with relay.lock:
            relay.ros_handle = ros_handle
            pending, relay.pending_feedback = relay.pending_feedback, None
        if pending is not None:
            ros_handle.publish_feedback(pending)
        try:
            while not relay.done.wait(0.2):
                if self._closing:
                    break
            goal = relay.zendock_goal
            client = self.client(action.name)
            with client.lock:
                status, result, error = goal.status, goal.result, goal.error
            client.forget(goal)
            try:
                ros_result = to_ros(result, result_class) if result is not None else result_class()
            except ConversionError as exc:
                self._refuse(
                    f"result-{action.name}", "could not put a %s result on ROS 2: %s", action.name, exc
                )
                ros_result, status = result_class(), GoalStatusCode.ABORTED
            if status == GoalStatusCode.SUCCEEDED:
                ros_handle.succeed()
            elif status == GoalStatusCode.CANCELED and ros_handle.is_cancel_requested:
                ros_handle.canceled()
            else:
                if error or not status.terminal:
                    self._refuse(
                        f"goal-lost-{action.name}",
                        "%s: zendock's goal ended without a result: %s",
                        action.name,
                        error or "its server went away",
                    )
                ros_handle.abort()
            self._count(f"result {action.name} {status.name}")
            return ros_result
        finally:
            with self._lock:
                if relay in self._active:
                    self._active.remove(relay)

    # --- bookkeeping ---------------------------------------------------------------------------------

    def _count(self, what: str) -> None:
        with self._counts_lock:
            self.counts[what] += 1

    def _refuse(self, kind: str, fmt: str, *args: object) -> None:
        self._count(f"refused {kind}")
        self._say.warning(kind, fmt, *args)

    def _report_stats(self) -> None:
        with self._counts_lock:
            counts = dict(sorted(self.counts.items()))
        if counts:
            self.node.log.info("samples %s", counts)

    def close(self) -> None:
        self._closing = True
        self._report_stats()
        self._services_watch.undeclare()
        for face in list(self.faces.values()):
            self._close_face(face)
        self.faces.clear()
        with self._lock:
            for outlet in self.outlets:
                if outlet.feed is not None:
                    outlet.feed.undeclare()
                    outlet.feed = None
        for executor in self.executors:
            executor.shutdown(timeout_sec=2.0)
        for thread in self._threads:
            thread.join(timeout=3.0)
        self._own.destroy_node()
        for context in self.contexts:
            context.try_shutdown()


SERVICE = ServiceSpec(
    "ros2_dds",
    Params,
    Ros2Dds,
    description="zendock's ROS 2 DDS face: real rclpy nodes (Jazzy, Fast DDS) for zendock's services",
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
