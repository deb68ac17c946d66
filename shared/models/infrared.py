"""The dock's infrared beacon and the robot's three infrared receivers, as Kobuki's docking station has them.

Kobuki's dock emits encoded infrared in three sectors (its left, centre and right), each in a near and a
far field; three receivers on the robot's front (right, central, left) each report which of the six
fields they see, one bit each (``kobuki_ros_interfaces/msg/DockInfraRed``: ``NEAR_LEFT`` 1, ``NEAR_CENTER``
2, ``NEAR_RIGHT`` 4, ``FAR_CENTER`` 8, ``FAR_LEFT`` 16, ``FAR_RIGHT`` 32; data ``[right, central, left]``).

Here the fields are sectors of the dock's face frame (x out of the dock, y to the dock's own left):

- centre: within ``centre_half_angle_rad`` of the dock's axis, never narrower than
  ``centre_min_half_width_m`` either side (the beam's width at the emitter);
- left / right: from ``side_inner_angle_rad`` to ``side_outer_angle_rad`` off the axis on that side, so
  that near the axis a receiver sees the centre and one side at once, as on the real dock;
- near within ``near_range_m`` of the emitter, far within ``far_range_m`` (a near receiver sees both).

A receiver sees a field when it stands in it, the emitter is within its own field of view, and the line
between them crosses no wall, box or dock body (infrared passes glass). Each bit a receiver should see
drops out with probability ``dropout`` per reading (sunlight, reflections), as real receivers flicker.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Annotated

import numpy as np
from msgspec import Meta

from shared.geometry import Pose2D, wrap_angle
from shared.messages import DockInfraRed
from shared.models.component import ComponentParams
from shared.models.raycast import SegmentSet, segment_blocked
from shared.world import DOCK_GEOMETRY, Dock

#: The receivers' field bits, as the message defines them.
NEAR_LEFT, NEAR_CENTER, NEAR_RIGHT = DockInfraRed.NEAR_LEFT, DockInfraRed.NEAR_CENTER, DockInfraRed.NEAR_RIGHT
FAR_CENTER, FAR_LEFT, FAR_RIGHT = DockInfraRed.FAR_CENTER, DockInfraRed.FAR_LEFT, DockInfraRed.FAR_RIGHT


@dataclass(frozen=True, slots=True)
class Receiver:
    """One infrared receiver on base_link, looking ``yaw_rad`` off the robot's heading."""

    x_m: float
    y_m: float
    yaw_rad: float
    half_fov_rad: float

    @property
    def mount(self) -> Pose2D:
        return Pose2D(self.x_m, self.y_m, self.yaw_rad)


class InfraredParams(ComponentParams, frozen=True):
    rate_hz: Annotated[
        float, Meta(gt=0, description="the receivers' readings (ir_dock) per second, while subscribed")
    ] = 20.0
    near_range_m: Annotated[float, Meta(gt=0)] = 0.6
    far_range_m: float = 2.5
    centre_half_angle_rad: float = math.radians(5.0)
    centre_min_half_width_m: float = 0.012
    side_inner_angle_rad: float = math.radians(0.5)
    side_outer_angle_rad: float = math.radians(75.0)
    #: Kobuki's order: right, central, left.
    receivers: tuple[Receiver, Receiver, Receiver] = (
        Receiver(0.10, -0.10, -math.radians(60.0), math.radians(55.0)),
        Receiver(0.13, 0.0, 0.0, math.radians(25.0)),
        Receiver(0.10, 0.10, math.radians(60.0), math.radians(55.0)),
    )
    dropout: Annotated[
        float, Meta(ge=0.0, lt=1.0, description="probability a bit a receiver should see drops out")
    ] = 0.03

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.near_range_m < self.far_range_m:
            raise ValueError("infrared ranges must satisfy 0 < near_range_m < far_range_m")


def fields_at(x: float, y: float, params: InfraredParams) -> int:
    """The fields (bits) a point ``(x, y)`` of the dock's face frame stands in."""
    if x <= 0.0:
        return 0
    distance = math.hypot(x, y)
    if distance > params.far_range_m:
        return 0
    bearing = math.atan2(y, x)
    near = distance <= params.near_range_m
    bits = 0
    if abs(y) <= max(params.centre_min_half_width_m, x * math.tan(params.centre_half_angle_rad)):
        bits |= FAR_CENTER | (NEAR_CENTER if near else 0)
    if params.side_inner_angle_rad <= bearing <= params.side_outer_angle_rad:
        bits |= FAR_LEFT | (NEAR_LEFT if near else 0)
    if -params.side_outer_angle_rad <= bearing <= -params.side_inner_angle_rad:
        bits |= FAR_RIGHT | (NEAR_RIGHT if near else 0)
    return bits


def receiver_readings(
    robot_pose: Pose2D,
    docks: Sequence[Dock],
    occluders: SegmentSet,
    params: InfraredParams,
    rng: np.random.Generator,
) -> tuple[int, int, int]:
    """What the right, central and left receivers read with the robot at ``robot_pose``."""
    readings = []
    for receiver in params.receivers:
        at = robot_pose.compose(receiver.mount)
        bits = 0
        for dock in docks:
            emitter = DOCK_GEOMETRY.marker_pose(dock)  # the face's centre, x out of the dock
            local = Pose2D(at.x, at.y).relative_to(emitter)
            seen = fields_at(local.x, local.y, params)
            if not seen:
                continue
            towards = math.atan2(emitter.y - at.y, emitter.x - at.x)
            if abs(wrap_angle(towards - at.yaw)) > receiver.half_fov_rad:
                continue
            if segment_blocked((at.x, at.y), (emitter.x, emitter.y), occluders):
                continue
            bits |= seen
        if bits and params.dropout > 0.0:
            for bit in (NEAR_LEFT, NEAR_CENTER, NEAR_RIGHT, FAR_CENTER, FAR_LEFT, FAR_RIGHT):
                if bits & bit and rng.random() < params.dropout:
                    bits &= ~bit
        readings.append(bits)
    return readings[0], readings[1], readings[2]


__all__ = [
    "FAR_CENTER",
    "FAR_LEFT",
    "FAR_RIGHT",
    "NEAR_CENTER",
    "NEAR_LEFT",
    "NEAR_RIGHT",
    "InfraredParams",
    "Receiver",
    "fields_at",
    "receiver_readings",
]
