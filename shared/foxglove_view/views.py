"""Which zendock topics have a Foxglove view, of which message type, and how each is received.

One table serves the live bridge (``python -m services.viz``) and the recorder (``zendock record``), so a
layout made on the live view opens recordings too. A view topic is the Zenoh key with a leading slash,
the way ROS users name topics: key ``robot1/scan`` is shown on ``/robot1/scan``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from shared import topics
from shared.foxglove_view import convert
from shared.foxglove_view.encoding import ViewMessage, ViewSchema
from shared.interfaces.map_server import COSTMAP_TOPIC
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
from shared.names import topic_key
from shared.schema import Message

#: View topics with no Zenoh key behind them (relative to the namespace like the others).
WORLD_VIEW_TOPIC = "world"
ROBOT_VIEW_TOPIC = "robot"


@dataclass(frozen=True, slots=True)
class View:
    """How one topic is shown.

    ``sensor``: a best-effort stream, subscribed with ``SENSOR_DATA``. ``latched``: rare and lasting
    (maps, the plan, static transforms): a viewer that subscribes late gets the latest at once.
    ``on_demand``: costly to make (camera frames are rendered only while someone subscribes): the live
    view subscribes on the bus only while a viewer watches it.
    """

    topic: str
    msg_type: type[Message]
    convert: Callable[[str, Any], list[ViewMessage]]
    sensor: bool = False
    latched: bool = False
    on_demand: bool = False
    #: The channel's schema, for on-demand views advertised before their first message.
    schema: ViewSchema | None = None


VIEWS: tuple[View, ...] = (
    View(topics.TF, TFMessage, convert.frame_transforms),
    View(topics.TF_STATIC, TFMessage, convert.frame_transforms, latched=True),
    View(topics.SCAN, LaserScan, convert.laser_scan, sensor=True),
    View(topics.ULTRASONIC, Range, convert.range_cone, sensor=True),
    View(topics.DETECTED_DOCK_POSE, PoseStamped, convert.pose_stamped, sensor=True),
    View(topics.MAP, OccupancyGrid, convert.occupancy_grid, latched=True),
    View(COSTMAP_TOPIC, OccupancyGrid, convert.costmap_grid, sensor=True, latched=True),
    View(topics.PLAN, Path, convert.path_poses, latched=True),
    View(topics.GROUND_TRUTH_POSE, PoseStamped, convert.pose_stamped),
    View(topics.POSE2D, Float64MultiArray, convert.pose2d_array),
    View(topics.BATTERY_STATUS, BatteryState, convert.battery_status),
    View(topics.DOCK_CONTACT, DockContact, convert.dock_contact),
    View(topics.COLLISIONS, CollisionEvent, convert.collision, latched=True),
    View(
        topics.CAMERA_IMAGE,
        Image,
        convert.raw_image,
        sensor=True,
        on_demand=True,
        schema=convert.RAW_IMAGE_SCHEMA,
    ),
    View(
        topics.ARUCO_DEBUG_IMAGE,
        Image,
        convert.raw_image,
        sensor=True,
        on_demand=True,
        schema=convert.RAW_IMAGE_SCHEMA,
    ),
)


def view_topic(namespace: str, topic: str) -> str:
    """The Foxglove topic of a zendock topic: ``/<namespace>/<topic>``."""
    return "/" + topic_key(namespace, topic)


def view_for_key(key: str) -> tuple[View, str] | None:
    """The view of a Zenoh key and the namespace it is in, e.g. ``robot1/scan`` -> (scan view, ``robot1``)."""
    for view in VIEWS:  # topics may have several segments (camera/image_raw)
        if key == view.topic:
            return view, ""
        if key.endswith("/" + view.topic):
            return view, key[: -len(view.topic) - 1]
    return None


def convert_key(key: str, type_name: str, payload: bytes) -> list[ViewMessage]:
    """The view messages of one raw sample, or none (no view, another type, or an invalid payload).

    Raises :class:`~shared.schema.MessageError` for a payload that does not decode as the view's type.
    """
    found = view_for_key(key)
    if found is None:
        return []
    view, _ = found
    if type_name and type_name != view.msg_type.TYPE_NAME:
        return []
    return view.convert("/" + key, view.msg_type.decode(payload))
