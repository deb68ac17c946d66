"""zendock's messages as Foxglove schemas, for the live view and for recordings (no bus in here).

- :mod:`~shared.foxglove_view.encoding`: :class:`ViewMessage`, an encoded message with its channel schema;
- :mod:`~shared.foxglove_view.convert`: one function per message type (tf, scan, range cone, grids, ...);
- :mod:`~shared.foxglove_view.scene`: the world file and the robot's footprint as scene entities;
- :mod:`~shared.foxglove_view.views`: which topic gets which view, and how it is subscribed.
"""

from shared.foxglove_view.encoding import ViewMessage, ViewSchema
from shared.foxglove_view.scene import DEFAULT_STAGING_OFFSET_M, robot_scene, staging_pose, world_scene
from shared.foxglove_view.views import (
    ROBOT_VIEW_TOPIC,
    VIEWS,
    WORLD_VIEW_TOPIC,
    View,
    convert_key,
    view_for_key,
    view_topic,
)

__all__ = [
    "DEFAULT_STAGING_OFFSET_M",
    "ROBOT_VIEW_TOPIC",
    "VIEWS",
    "WORLD_VIEW_TOPIC",
    "View",
    "ViewMessage",
    "ViewSchema",
    "convert_key",
    "robot_scene",
    "staging_pose",
    "view_for_key",
    "view_topic",
    "world_scene",
]
