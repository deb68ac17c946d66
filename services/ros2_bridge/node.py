"""The ROS 2 bridge: zendock's keys as a ROS 2 (rmw_zenoh, Jazzy) graph on the same router.

A ROS 2 machine running rmw_zenoh that connects to zendock's router sees a node per zendock service
(``simulator``, ``battery``, ``pose``, ``planner``, ``perception``, ``docking``) with its publishers,
subscriptions and action services, announced by liveliness tokens in rmw_zenoh's form
(:mod:`shared.ros2.wire`) while the service itself is up (:mod:`.graph`), and exchanges CDR samples with
them on rmw_zenoh's data keys:

* zendock -> ROS 2 (:data:`~shared.ros2.bridge_routes.OUTBOUND`): a key is read and forwarded only
  while a ROS 2 subscription for its topic exists (the peer's token says so). Transient-local topics
  (``/map``, ``/tf_static``, actions' status) are always read and always published, through zenoh-ext's
  AdvancedPublisher configured as rmw_zenoh configures a TRANSIENT_LOCAL publisher (a cache as deep as
  the history, publisher detection, sporadic heartbeats when reliable): a late rmw_zenoh subscriber (an
  AdvancedSubscriber with history and late-publisher detection) takes the cached samples itself.
* Every sample's attachment carries what rmw_zenoh's does: a sequence number starting at 1 and the
  publisher's gid, the hash of its liveliness token key (:func:`shared.ros2.wire.entity_gid`).
* Each node serves ``rcl_interfaces``' parameter services (``ros2 param``), answered from its zendock
  service's parameters (:mod:`.parameters`).
* ROS 2 -> zendock: ``/cmd_vel`` (Twist or TwistStamped) drives the robot; ``/goal_pose`` (what RViz's
  goal tool sends) becomes a ``navigate_to_pose`` goal; ``/initialpose`` (RViz's pose estimate) sets what
  the simulated localiser believes (``simulator/set_localisation``).

zendock's own keys and msgpack payloads are untouched: the bridge is one more service on the bus.
Anything malformed from ROS 2 (bytes that are not CDR of the type, a type hash that is not Jazzy's, a
goal in a frame zendock does not plan in) is counted and logged at most once per interval per kind.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass
from typing import Annotated, Any

import msgspec
import zenoh
import zenoh.ext
from msgspec import Meta

from services.ros2_bridge.actions import ACTIONS, SERVICES, ActionRelay, QueryRelay
from services.ros2_bridge.demand import PeerSubscriptions
from services.ros2_bridge.graph import GraphMirror
from services.ros2_bridge.parameters import ParameterRelay
from shared.messages import PoseStamped
from shared.names import node_token_key, parse_token_key
from shared.navigation import NavigationClient
from shared.node import SENSOR_DATA, Node, QoS, Subscription
from shared.parameters import ServiceParams
from shared.ratelimit import RateLimitedLogger
from shared.ros2 import interfaces as ros_interfaces
from shared.ros2 import types as ros_types
from shared.ros2.bridge_routes import (
    INBOUND,
    OUTBOUND,
    TWIST_STAMPED,
    Inbound,
    Route,
    default_domain_id,
)
from shared.ros2.commands import RosCommands
from shared.ros2.wire import (
    ADMIN_SPACE,
    Attachment,
    Endpoint,
    EntityKind,
    GraphNode,
    QosProfile,
    Reliability,
    data_key,
    dds_type_name,
    entity_gid,
    namespace_error,
    qualified_name,
)
from shared.ros2.wire import RELIABLE as ROS_RELIABLE
from shared.runtime import ServiceSpec
from shared.schema import MessageError

STATS_PERIOD_S = 30.0
BRIDGE_NODE = "ros2_bridge"
#: rmw_zenoh's SAMPLE_MISS_DETECTION_HEARTBEAT_PERIOD (rmw_publisher_data.cpp): a reliable transient-local
#: publisher sends its last sequence number this often, when it changed, so subscribers recover a lost sample.
HEARTBEAT_PERIOD_S = 0.5
#: rmw_zenoh's publishers number their samples from 1 (PublisherData's sequence_number_).
FIRST_SEQUENCE_NUMBER = 1


class Params(ServiceParams):
    """Parameters of ``python -m services.ros2_bridge``."""

    domain_id: Annotated[
        int, Meta(ge=0, le=232, description="ROS 2 domain (default: ROS_DOMAIN_ID, else 0)")
    ] = msgspec.field(default_factory=default_domain_id)
    ros_namespace: Annotated[
        str,
        Meta(
            description="ROS 2 namespace the zendock robot's topics and nodes appear "
            "in, in rcl's canonical form (/ or /robot)"
        ),
    ] = "/"

    def __post_init__(self) -> None:
        error = namespace_error(self.ros_namespace)
        if error is not None:
            raise ValueError(f"ros_namespace: not a canonical ROS namespace: {error}")


@dataclass
class _Outlet:
    """One outbound route's ROS 2 side: its publisher, gid and next sequence number, and what feeds it."""

    route: Route
    topic: str
    type_hash: str
    publisher: Any
    gid: bytes
    sequence: int = FIRST_SEQUENCE_NUMBER
    feed: Subscription[Any] | None = None


class Ros2Bridge:
    def __init__(self, node: Node, params: Params) -> None:
        self.node = node
        self.params = params
        self.session = node.session
        self.session_id = str(node.session.info.zid())
        self.counts: Counter[str] = Counter()
        self._say = RateLimitedLogger(node.log, interval_s=5.0)
        self._subscribers: list[Any] = []
        self.peers = PeerSubscriptions(self.session_id, params.domain_id)
        self.graph = GraphMirror(self._graph_nodes(), self.session.liveliness().declare_token, BRIDGE_NODE)
        self._entity_ids = iter(range(len(self.graph.nodes) + 1, 1 << 30))
        self.outlets: dict[str, _Outlet] = {}
        for route in OUTBOUND:
            self._open_outlet(route)
        self._commands = RosCommands(node, self._refuse, self._navigate)
        self._navigation = NavigationClient(node)
        for ros_topic in dict.fromkeys(i.ros_topic for i in INBOUND):
            self._open_inlet(ros_topic, [i for i in INBOUND if i.ros_topic == ros_topic])
        self.actions = [self._open_action(action) for action in ACTIONS]
        self.services = self._open_services()
        self.parameters = self._open_parameters()
        # zendock's services, past and future: which of them ROS 2 sees.
        self._services_watch = self.session.liveliness().declare_subscriber(
            node_token_key(node.namespace, "*"), self._on_service_token, history=True
        )
        # Peers' subscriptions, past and future: what to forward.
        self._graph_watch = self.session.liveliness().declare_subscriber(
            f"{ADMIN_SPACE}/{params.domain_id}/**", self._on_graph_token, history=True
        )
        node.create_timer(STATS_PERIOD_S, self._report_stats, wall=True)
        node.log.info(
            "ROS 2 domain %d, namespace %s: %d topics out, %d in, %d actions, %d services, session %s",
            params.domain_id,
            params.ros_namespace,
            len(OUTBOUND),
            len(INBOUND),
            len(ACTIONS),
            len(SERVICES),
            self.session_id,
        )

    # --- the graph zendock shows to ROS 2 ---------------------------------------------------------

    def _graph_nodes(self) -> dict[str, GraphNode]:
        owners = [
            BRIDGE_NODE,
            *(r.owner for r in OUTBOUND),
            *(i.owner for i in INBOUND),
            *(a.owner for a in ACTIONS),
            *(bridged.owner for bridged, _relayed in SERVICES),
        ]
        return {
            name: GraphNode(self.params.domain_id, self.session_id, i, name, self.params.ros_namespace)
            for i, name in enumerate(dict.fromkeys(owners))
        }

    def _declare_endpoint(
        self, owner: str, kind: EntityKind, topic: str, ros_type: str, type_hash: str, qos: QosProfile
    ) -> Endpoint:
        endpoint = Endpoint(
            self.graph.nodes[owner], next(self._entity_ids), kind, topic, ros_type, type_hash, qos
        )
        self.graph.add(endpoint)
        return endpoint

    def _on_service_token(self, sample: zenoh.Sample) -> None:
        entry = parse_token_key(str(sample.key_expr))
        if entry is not None:
            self.node.post(self._service_changed, entry.node, sample.kind == zenoh.SampleKind.PUT)

    def _service_changed(self, name: str, alive: bool) -> None:
        if alive and self.graph.present(name):
            self.node.log.info("zendock's %s is up: ROS 2 sees node %s", name, name)
        elif not alive and self.graph.absent(name):
            self.node.log.info("zendock's %s is gone: its ROS 2 node is withdrawn", name)

    def ros_topic(self, name: str) -> str:
        return qualified_name(self.params.ros_namespace, name)

    # --- zendock -> ROS 2 -------------------------------------------------------------------------

    def _open_outlet(self, route: Route) -> None:
        topic = self.ros_topic(route.ros_topic)
        type_hash = ros_types.type_hash(route.ros_type)
        endpoint = self._declare_endpoint(
            route.owner, EntityKind.PUBLISHER, topic, route.ros_type, type_hash, route.qos
        )
        best_effort = route.qos.reliability is Reliability.BEST_EFFORT
        key = data_key(self.params.domain_id, topic, route.ros_type, type_hash)
        options: dict[str, Any] = {
            "reliability": zenoh.Reliability.BEST_EFFORT if best_effort else zenoh.Reliability.RELIABLE,
            "congestion_control": zenoh.CongestionControl.DROP
            if best_effort
            else zenoh.CongestionControl.BLOCK,
        }
        publisher: zenoh.Publisher | zenoh.ext.AdvancedPublisher
        if route.latched:
            publisher = zenoh.ext.declare_advanced_publisher(
                self.session, key, **options, **_transient_local(route.qos)
            )
        else:
            publisher = self.session.declare_publisher(key, **options)
        outlet = _Outlet(route, topic, type_hash, publisher, entity_gid(endpoint.token_key()))
        self.outlets[topic] = outlet
        if route.latched:
            self._feed(outlet)

    def _feed(self, outlet: _Outlet) -> None:
        qos = SENSOR_DATA if outlet.route.qos.reliability is Reliability.BEST_EFFORT else QoS(depth=10)
        outlet.feed = self.node.create_subscription(
            outlet.route.zendock_type, outlet.route.zendock_topic, lambda msg: self._forward(outlet, msg), qos
        )

    def _forward(self, outlet: _Outlet, msg: Any) -> None:
        # A transient-local publisher's cache must hold the last messages before anyone asks for them.
        if not outlet.route.latched and not self.peers.wanted(outlet.topic):
            return
        try:
            payload = ros_types.to_cdr(msg, outlet.route.ros_type)
        except ros_types.Ros2TypeError as exc:
            self._refuse(f"encode-{outlet.topic}", "could not put %s on ROS 2: %s", outlet.topic, exc)
            return
        attachment = Attachment(outlet.sequence, time.time_ns(), outlet.gid).encode()
        outlet.sequence += 1
        outlet.publisher.put(payload, attachment=attachment)
        self.counts[f"out {outlet.topic}"] += 1

    def _on_graph_token(self, sample: zenoh.Sample) -> None:
        # Zenoh's thread: hand the token to the executor, where the subscriptions it changes live.
        self.node.post(self._graph_changed, str(sample.key_expr), sample.kind == zenoh.SampleKind.PUT)

    def _graph_changed(self, key: str, alive: bool) -> None:
        try:
            endpoint = self.peers.appeared(key) if alive else self.peers.vanished(key)
        except ValueError as exc:
            self._refuse("graph-token", "ignored a graph token: %s", exc)
            return
        if endpoint is None:
            return
        outlet = self.outlets.get(endpoint.topic)
        if outlet is None:
            return
        if alive:
            self._check_type(outlet, endpoint)
        wanted = self.peers.wanted(outlet.topic)
        if wanted and outlet.feed is None:
            self._feed(outlet)
            self.node.log.info(
                "a ROS 2 node subscribes to %s: forwarding %s",
                outlet.topic,
                self.node.key(outlet.route.zendock_topic),
            )
        elif not wanted and outlet.feed is not None and not outlet.route.latched:
            outlet.feed.undeclare()
            outlet.feed = None
            self.node.log.info("no ROS 2 subscription to %s left: no longer forwarding it", outlet.topic)

    def _check_type(self, outlet: _Outlet, endpoint: Endpoint) -> None:
        if endpoint.ros_type != outlet.route.ros_type or endpoint.type_hash != outlet.type_hash:
            self._refuse(
                "type-mismatch",
                "node %s subscribes to %s as %s (%s); zendock publishes %s (%s): "
                "their samples will not match",
                endpoint.node.name,
                outlet.topic,
                endpoint.ros_type,
                endpoint.type_hash,
                outlet.route.ros_type,
                outlet.type_hash,
            )

    # --- ROS 2 -> zendock -------------------------------------------------------------------------

    def _open_inlet(self, ros_topic: str, accepted: list[Inbound]) -> None:
        """One subscription per topic, any type and hash: a sample of a type zendock does not take, or
        under a hash that is not Jazzy's, is refused by name rather than silently never seen."""
        topic = self.ros_topic(ros_topic)
        by_dds_type = {dds_type_name(i.ros_type): (i, ros_types.type_hash(i.ros_type)) for i in accepted}
        for inbound, type_hash in by_dds_type.values():
            self._declare_endpoint(
                inbound.owner, EntityKind.SUBSCRIPTION, topic, inbound.ros_type, type_hash, ROS_RELIABLE
            )

        def on_sample(sample: zenoh.Sample) -> None:
            self.node.post(self._receive, topic, by_dds_type, str(sample.key_expr), sample.payload.to_bytes())

        key = f"{self.params.domain_id}/{topic.strip('/')}/*/*"
        self._subscribers.append(self.session.declare_subscriber(key, on_sample))

    def _receive(
        self, topic: str, by_dds_type: dict[str, tuple[Inbound, str]], key: str, payload: bytes
    ) -> None:
        dds_type, sent_hash = key.rsplit("/", 2)[-2:]
        if dds_type not in by_dds_type:
            self._refuse(
                f"type-{topic}",
                "refused %s as %s: zendock takes %s there",
                topic,
                dds_type,
                " or ".join(i.ros_type for i, _ in by_dds_type.values()),
            )
            return
        inbound, type_hash = by_dds_type[dds_type]
        if sent_hash != type_hash:
            self._refuse(
                f"hash-{topic}",
                "refused %s: type hash %s is not Jazzy's %s for %s",
                topic,
                sent_hash,
                type_hash,
                inbound.ros_type,
            )
            return
        try:
            ros_msg = ros_types.from_cdr(payload, inbound.ros_type)
            if inbound.ros_type == TWIST_STAMPED:
                ros_msg = ros_msg.twist
            msg = ros_types.from_ros(ros_msg, inbound.zendock_type)
        except (ros_types.Ros2TypeError, MessageError) as exc:
            self._refuse(f"malformed-{topic}", "refused a message on %s: %s", topic, exc)
            return
        self.counts[f"in {topic}"] += 1
        self._commands.handle(inbound.ros_topic, msg)

    def _navigate(self, goal: PoseStamped) -> None:
        self._navigation.go_to_pose(goal.pose.to_pose2d())

    # --- actions: ROS 2 goals for zendock's action servers ---------------------------------------

    def _open_action(self, action: Any) -> ActionRelay:
        name = self.ros_topic(action.name)
        for service in action.services:
            self._declare_endpoint(
                action.owner,
                EntityKind.SERVICE,
                f"{name}/_action/{service.part}",
                service.ros_type,
                ros_types.type_hash(service.ros_type),
                ROS_RELIABLE,
            )
        return ActionRelay(self.node, action, self.params.domain_id, name, self._refuse, self._count)

    def _open_services(self) -> QueryRelay:
        """zendock's plain services (Nav2's lifecycle queries) as ROS 2 services of their owners' nodes."""
        relay = QueryRelay(self.node, self.params.domain_id, self._refuse, self._count)
        for bridged, relayed in SERVICES:
            name = self.ros_topic(bridged.name)
            type_hash = ros_types.type_hash(bridged.ros_type)
            self._declare_endpoint(
                bridged.owner, EntityKind.SERVICE, name, bridged.ros_type, type_hash, ROS_RELIABLE
            )
            relay.serve(name, relayed, bridged.name)
        return relay

    def _open_parameters(self) -> ParameterRelay:
        """Each node's ``rcl_interfaces`` parameter services, answered from its zendock service's parameters."""
        relay = ParameterRelay(self.node, self.params.domain_id, self._refuse, self._count)
        for owner in self.graph.nodes:
            for verb, (ros_type, _request, _response) in ros_interfaces.PARAMETER_SERVICES.items():
                name = self.ros_topic(f"{owner}/{verb}")
                type_hash = ros_types.type_hash(ros_type)
                self._declare_endpoint(owner, EntityKind.SERVICE, name, ros_type, type_hash, ROS_RELIABLE)
                relay.serve(owner, verb, name)
        return relay

    def _count(self, what: str) -> None:
        self.counts[what] += 1

    # --- bookkeeping ------------------------------------------------------------------------------

    def _refuse(self, kind: str, fmt: str, *args: object) -> None:
        self.counts[f"refused {kind}"] += 1
        self._say.warning(kind, fmt, *args)

    def _report_stats(self) -> None:
        if self.counts:
            self.node.log.info("samples %s", dict(sorted(self.counts.items())))

    def close(self) -> None:
        self._report_stats()
        self._graph_watch.undeclare()
        self._services_watch.undeclare()
        for subscriber in self._subscribers:
            subscriber.undeclare()
        for relay in self.actions:
            relay.close()
        self.services.close()
        self.parameters.close()
        for outlet in self.outlets.values():
            outlet.publisher.undeclare()
        self.graph.close()


def _transient_local(qos: QosProfile) -> dict[str, Any]:
    """AdvancedPublisher options for a TRANSIENT_LOCAL publisher, as rmw_zenoh sets them
    (``rmw_publisher_data.cpp``, ``PublisherData::make``): a cache of ``depth`` samples, a liveliness token
    under ``@adv/pub`` so late subscribers detect the publisher, and, when reliable, sporadic heartbeats."""
    options: dict[str, Any] = {"cache": zenoh.ext.CacheConfig(qos.depth), "publisher_detection": True}
    if qos.reliability is Reliability.RELIABLE:
        options["sample_miss_detection"] = zenoh.ext.MissDetectionConfig(
            heartbeat=None, sporadic_heartbeat=HEARTBEAT_PERIOD_S
        )
    return options


SERVICE = ServiceSpec(
    "ros2_bridge",
    Params,
    Ros2Bridge,
    description="zendock ROS 2 bridge: zendock's keys on rmw_zenoh's wire (ROS 2 Jazzy)",
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
