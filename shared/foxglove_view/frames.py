"""Several robots in one view: each robot's frames under its name, all under the one shared map.

Every robot's transforms name the same frames (``odom``, ``base_link``, ``lidar_link``, ...). Shown
side by side they would fight over one tree, so each robot's messages get their frame ids prefixed with
the robot's name (``r1/base_link``) before they are converted; ``map``, the frame the robots share, and
an empty frame id stay as they are.
"""

from __future__ import annotations

import dataclasses
from typing import Any

#: Frames every robot of a room shares.
SHARED_FRAMES = frozenset({"", "map"})
_FRAME_FIELDS = ("frame_id", "child_frame_id")


def robot_frame(robot: str, frame: str) -> str:
    """``frame`` of ``robot`` as the shared view names it."""
    return frame if frame in SHARED_FRAMES or not robot else f"{robot}/{frame}"


def prefix_frames(msg: Any, robot: str) -> Any:
    """A copy of ``msg`` with every ``frame_id`` and ``child_frame_id`` in it (headers, transforms, poses of
    a path) put under ``robot``. A copy, not a change: a received message is shared with the process's other
    subscriptions on its key (:class:`~shared.endpoints.SharedDecodes`)."""
    if not robot or not dataclasses.is_dataclass(msg) or isinstance(msg, type):
        return msg
    changes: dict[str, Any] = {}
    for f in dataclasses.fields(msg):
        value = getattr(msg, f.name)
        if f.name in _FRAME_FIELDS and isinstance(value, str):
            changes[f.name] = robot_frame(robot, value)
        elif dataclasses.is_dataclass(value):
            changes[f.name] = prefix_frames(value, robot)
        elif isinstance(value, list) and value and dataclasses.is_dataclass(value[0]):
            changes[f.name] = [prefix_frames(item, robot) for item in value]
    return dataclasses.replace(msg, **changes)
