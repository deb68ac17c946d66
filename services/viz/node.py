"""The live view's wiring: zendock topics in, Foxglove channels out (WebSocket, port 8765 by default).

Subscribes every topic of :data:`shared.foxglove_view.VIEWS` in the node's namespace (sensor streams
best effort, with ``SENSOR_DATA``), converts each message to its Foxglove schema and logs it on the
server. A stream nobody watches is not converted. The world file (optional) is drawn as a scene on
``/world`` with each dock's staging pose; the robot's footprint is on ``/robot``. Rare topics (the map,
the plan, static transforms, the scenes) are latched: a viewer that subscribes late gets the latest at
once. The map is also asked for once at start, since Zenoh keeps no history for late joiners.

Only the bus is touched through the node; the server's own threads just post "someone subscribed" to the
node's executor. Restarting this service changes nothing for the others: it only listens.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated, Any

import msgspec
from msgspec import Meta

from services.viz.live_view import LiveView
from shared.config_errors import ConfigError
from shared.foxglove_view import (
    DEFAULT_STAGING_OFFSET_M,
    ROBOT_VIEW_TOPIC,
    VIEWS,
    WORLD_VIEW_TOPIC,
    View,
    robot_scene,
    view_topic,
    world_scene,
)
from shared.foxglove_view.frames import prefix_frames, robot_frame
from shared.interfaces.map_server import GET_MAP, GET_MAP_SERVICE, GetMapRequest, GetMapResponse
from shared.messages import OccupancyGrid
from shared.names import topic_key
from shared.node import SENSOR_DATA, Node, QoS, ServiceError, Subscription
from shared.parameters import ServiceParams
from shared.runtime import ServiceSpec
from shared.schema import Message
from shared.structs import blaming
from shared.topics import BASE_FRAME, MAP
from shared.world import World, load_world

#: Latched topics keep only the latest; a map or a plan arrives rarely.
LATCHED_QOS = QoS(depth=2)
#: Everything else that is reliable (tf, poses, battery): a short queue, the view only shows the latest.
STATE_QOS = QoS(depth=10)
MAP_REQUEST_PERIOD_S = 5.0
#: How often the live view checks whether a viewer watches an on-demand stream (wall seconds).
ON_DEMAND_CHECK_S = 0.5
#: The view's default Zenoh settings: no shared memory (see the file), which keeps its RSS under 100 MB.
ZENOH_CONFIG = Path(__file__).with_name("zenoh.json5")
MAP_VIEW = next(v for v in VIEWS if v.topic == MAP and v.msg_type is OccupancyGrid)


class Params(ServiceParams):
    """Parameters of ``python -m services.viz`` (``-p name=value``)."""

    use_sim_time: Annotated[bool, Meta(description="stamp and broadcast on the simulator's clock")] = True
    host: Annotated[
        str, Meta(description="address to serve on (loopback: only this machine can connect)")
    ] = "127.0.0.1"
    port: Annotated[int, Meta(ge=0, le=65535, description="WebSocket port (0: any free port)")] = 8765
    world: Annotated[
        str | None, Meta(description="world file to draw walls, glass, boxes, docks and staging poses")
    ] = None
    staging_offset_m: Annotated[float, Meta(ge=0.0, description="staging pose behind each dock")] = (
        DEFAULT_STAGING_OFFSET_M
    )
    time_broadcast_hz: Annotated[
        float, Meta(gt=0.0, le=100.0, description="how often viewers are told the time")
    ] = 10.0
    robots: Annotated[
        list[str],
        Meta(
            description="a fleet's robots (namespaces under the node's) "
            "shown side by side, each one's frames under its name (r1/base_link) below the "
            "shared map; empty: the node's own namespace, one robot"
        ),
    ] = msgspec.field(default_factory=list)

    def __post_init__(self) -> None:
        if self.world:
            with blaming("world"):
                load_world(self.world)  # a ConfigError names the file and the problem
        self.world = self.world or None


class VizService:
    """Bridges the node's namespace to a Foxglove WebSocket server; see the module docstring."""

    def __init__(self, node: Node, params: Params) -> None:
        self._node = node
        self._params = params
        self._log = node.log
        self._world: World | None = load_world(params.world) if params.world else None
        try:
            self._view = LiveView(params.host, params.port, self._now_ns, self._on_viewer_subscribed)
        except RuntimeError as exc:  # the SDK's FoxgloveError: the port is taken, the address is not ours
            raise ConfigError(
                f"cannot serve on {params.host}:{params.port}: {exc} (choose another with --port)"
            ) from None
        self._world_topic = view_topic(node.namespace, WORLD_VIEW_TOPIC)
        #: Each robot shown: its name (the frame prefix, "" for a lone robot) and its namespace.
        self._robots = (
            [(r, topic_key(node.namespace, r)) for r in params.robots]
            if params.robots
            else [("", node.namespace)]
        )
        self._map_received = False
        self._publish_scenes()
        #: On-demand views (camera frames): the Foxglove topic, and the bus subscription while a viewer watches.
        self._on_demand: dict[str, tuple[View, str, str, Subscription[Any] | None]] = {}
        for robot, namespace in self._robots:
            for view in VIEWS:
                if view.on_demand and view.schema is not None:
                    topic = view_topic(namespace, view.topic)
                    self._view.advertise(topic, view.schema)
                    self._on_demand[topic] = (view, robot, namespace, None)
                else:
                    self._subscribe(view, robot, namespace)
        self._demand_timer = node.create_timer(ON_DEMAND_CHECK_S, self._follow_viewers, wall=True)
        self._time_timer = node.create_timer(1.0 / params.time_broadcast_hz, self._broadcast_time, wall=True)
        self._map_timer = node.create_timer(MAP_REQUEST_PERIOD_S, self._request_map, wall=True)
        self._request_map()
        self._log.info(
            "Foxglove WebSocket on ws://%s:%d (open it in Foxglove or Lichtblick)%s",
            params.host,
            self._view.port,
            f", world {self._world.name}" if self._world else "",
        )

    @property
    def port(self) -> int:
        return self._view.port

    # --- time ------------------------------------------------------------------------------------

    def _now_ns(self) -> int:
        """Now on the robot's clock (sim time once the clock runs), for messages without a stamp."""
        node = self._node
        if node.use_sim_time and node.clock_started:
            return int(node.now() * 1e9)
        return time.time_ns()

    def _broadcast_time(self) -> None:
        if self._node.use_sim_time and self._node.clock_started:
            self._view.broadcast_time(self._now_ns())

    # --- inputs ----------------------------------------------------------------------------------

    def _subscribe(self, view: View, robot: str, namespace: str) -> Subscription[Any]:
        qos = SENSOR_DATA if view.sensor else LATCHED_QOS if view.latched else STATE_QOS
        return self._node.create_subscription(
            view.msg_type,
            topic_key(namespace, view.topic),
            lambda key, msg, v=view, r=robot: self._on_message(v, key, msg, r),
            qos,
            with_key=True,
            absolute=True,
        )

    def _follow_viewers(self) -> None:
        """Subscribe to an on-demand stream while a viewer watches it, so frames are made only then."""
        for topic, (view, robot, namespace, sub) in self._on_demand.items():
            watched = self._view.has_viewer(topic)
            if watched and sub is None:
                self._on_demand[topic] = (view, robot, namespace, self._subscribe(view, robot, namespace))
                self._log.info("a viewer watches %s: subscribing", topic)
            elif not watched and sub is not None:
                sub.undeclare()
                self._on_demand[topic] = (view, robot, namespace, None)
                self._log.info("no viewer on %s: unsubscribed", topic)

    def _on_message(self, view: View, key: str, msg: Message, robot: str = "") -> None:
        if view.topic == MAP:
            self._map_received = True
        if not view.latched and not self._view.wants(key):
            return
        self._view.publish(key, view.convert("/" + key, prefix_frames(msg, robot)), latched=view.latched)

    def _request_map(self) -> None:
        if self._map_received:
            self._map_timer.cancel()
            return
        self._node.call_async(
            GET_MAP,
            topic_key(self._robots[0][1], GET_MAP_SERVICE),
            GetMapRequest(),
            self._on_map_reply,
            timeout_s=2.0,
            absolute=True,
        )

    def _on_map_reply(self, response: GetMapResponse | None, error: ServiceError | None) -> None:
        if response is None or self._map_received:
            if error is not None:
                self._log.debug("no map yet: %s", error)
            return
        robot, namespace = self._robots[0]
        self._on_message(MAP_VIEW, topic_key(namespace, MAP), response.map, robot)

    # --- the scenes and late viewers -------------------------------------------------------------

    def _publish_scenes(self) -> None:
        now = self._now_ns()
        if self._world is not None:
            scene = world_scene(self._world_topic, self._world, now, self._params.staging_offset_m)
            self._view.publish(self._world_topic, [scene], latched=True)
        for robot, namespace in self._robots:
            topic = view_topic(namespace, ROBOT_VIEW_TOPIC)
            self._view.publish(topic, [robot_scene(topic, now, robot_frame(robot, BASE_FRAME))], latched=True)

    def _on_viewer_subscribed(self, topic: str) -> None:
        """Runs on the server's thread: hand over to the node's executor."""
        self._node.post(self._view.replay_latched, topic)

    @property
    def messages_sent(self) -> int:
        return self._view.sent

    def close(self) -> None:
        self._time_timer.cancel()
        self._map_timer.cancel()
        self._demand_timer.cancel()
        self._view.close()


def _add_flags(parser: Any) -> dict[str, str]:
    parser.set_defaults(zenoh_config=str(ZENOH_CONFIG))
    parser.add_argument("--port", type=int, default=None, help="WebSocket port (same as -p port=N)")
    parser.add_argument("--host", default=None, help="address to serve on (same as -p host=ADDR)")
    parser.add_argument("--world", default=None, help="world file to draw (same as -p world=FILE)")
    return {"port": "port", "host": "host", "world": "world"}


SERVICE = ServiceSpec(
    "viz",
    Params,
    VizService,
    description="Live view: zendock topics on a Foxglove WebSocket server",
    add_flags=_add_flags,
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
