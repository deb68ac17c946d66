"""The viz service's contract."""

from __future__ import annotations

from shared import topics
from shared.contracts.model import Contract, Flag, Request, Topic
from shared.contracts.services.common import IMAGE_QOS
from shared.endpoints import SENSOR_DATA, QoS
from shared.interfaces.map_server import COSTMAP_TOPIC, GET_MAP, GET_MAP_SERVICE
from shared.messages import (
    BatteryState,
    CollisionEvent,
    DockContact,
    Float64MultiArray,
    Image,
    LaserScan,
    OccupancyGrid,
    Path,
    PoseStamped,
    Range,
    TFMessage,
)

CONTRACT = Contract(
    service="viz",
    summary="A Foxglove WebSocket view of the robot(s): map, costmap, scans, sonar, plan, battery, poses.",
    version="1.1",
    subscribes=(
        Topic(topics.BATTERY_STATUS, BatteryState, QoS(depth=5)),
        Topic(topics.COLLISIONS, CollisionEvent, QoS(depth=5)),
        Topic(COSTMAP_TOPIC, OccupancyGrid, SENSOR_DATA),
        Topic(topics.DETECTED_DOCK_POSE, PoseStamped, SENSOR_DATA),
        Topic(topics.DOCK_CONTACT, DockContact, QoS(depth=5)),
        Topic(topics.GROUND_TRUTH_POSE, PoseStamped, QoS(depth=5)),
        Topic(topics.MAP, OccupancyGrid, QoS(depth=1)),
        Topic(topics.POSE2D, Float64MultiArray, QoS(depth=5)),
        Topic(topics.PLAN, Path, QoS(depth=5)),
        Topic(topics.SCAN, LaserScan, SENSOR_DATA),
        Topic(topics.TF, TFMessage, QoS(depth=5)),
        Topic(topics.TF_STATIC, TFMessage, QoS(depth=5)),
        Topic(topics.ULTRASONIC, Range, SENSOR_DATA),
        Topic(topics.CAMERA_IMAGE, Image, IMAGE_QOS, when="while a viewer watches it"),
        Topic(topics.ARUCO_DEBUG_IMAGE, Image, IMAGE_QOS, when="while a viewer watches it"),
    ),
    calls=(Request(GET_MAP_SERVICE, GET_MAP, about="the map, once, if none arrived"),),
    flags=(Flag("world", "the world file to draw (as --world)"), Flag("port", "WebSocket port (loopback)")),
    notes=(
        "Its behaviour is a WebSocket server for viewers, outside the bus; conform checks its endpoints only.",
    ),
)
