"""Frame names, the robot's sensor mounts from ``tf_static``, and when a clock counts as reset.

Every service that places sensor readings needs the mounts of its sensors on base_link, which the
simulator publishes once on ``tf_static`` (latched). The rules for reading them live here once: tf's
frame names ignore a leading ``/``, and only transforms whose parent is base_link are mounts.
"""

from __future__ import annotations

from shared.geometry import Pose2D
from shared.messages import TFMessage
from shared.topics import BASE_FRAME

#: A clock reading this much earlier than the newest one is a reset (the simulator restarted), not
#: jitter: histories keyed on that clock are dropped rather than kept out of order.
CLOCK_RESET_S = 1.0


def frame_name(name: str) -> str:
    """A frame name as tf compares it: without leading slashes (``/base_link`` is ``base_link``)."""
    return name.lstrip("/")


def clock_went_back(now_s: float, last_s: float | None) -> bool:
    """Whether ``now_s`` is a reset of the clock that last read ``last_s`` (see :data:`CLOCK_RESET_S`)."""
    return last_s is not None and now_s < last_s - CLOCK_RESET_S


class SensorMounts:
    """The pose of each sensor frame on base_link, as ``tf_static`` last said (or as configured)."""

    def __init__(self, defaults: dict[str, Pose2D] | None = None) -> None:
        self._mounts = {frame_name(frame): pose for frame, pose in (defaults or {}).items()}

    def update(self, msg: TFMessage) -> list[str]:
        """Take the base_link children of a ``tf_static`` message; returns the frames it set."""
        updated = []
        for item in msg.transforms:
            child = frame_name(item.child_frame_id)
            if frame_name(item.header.frame_id) == BASE_FRAME and child:
                self._mounts[child] = item.transform.to_pose2d()
                updated.append(child)
        return updated

    def get(self, frame: str) -> Pose2D | None:
        """The mount of ``frame`` on base_link, or ``None`` when none is known."""
        return self._mounts.get(frame_name(frame))
