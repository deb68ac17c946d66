"""zendock messages as Foxglove schemas: what Foxglove (or Lichtblick) can draw and plot.

Pure functions from a decoded message to :class:`~shared.foxglove_view.encoding.ViewMessage` s; no bus.
The mapping follows foxglove_bridge's ROS 2 conversions where one exists: ``tf`` becomes
``foxglove.FrameTransforms``, ``LaserScan`` becomes ``foxglove.LaserScan`` (out-of-range readings become
NaN, which Foxglove leaves undrawn), ``OccupancyGrid`` becomes ``foxglove.Grid`` with RGBA cells, a
``Path`` becomes ``foxglove.PosesInFrame``. An ultrasonic ``Range`` is drawn as its cone, as RViz does.
"""

from __future__ import annotations

import math

import numpy as np
from foxglove import messages as fg

from shared.foxglove_view.encoding import (
    ViewMessage,
    json_schema,
    json_view,
    protobuf_schema,
    protobuf_view,
    stamp_ns,
    timestamp,
)
from shared.messages import (
    BatteryState,
    CollisionEvent,
    DockContact,
    Float64MultiArray,
    Image,
    LaserScan,
    OccupancyGrid,
    Path,
    Pose,
    PoseStamped,
    Range,
    TFMessage,
)
from shared.topics import MAP_FRAME

#: A quarter turn about y: a cylinder's z axis (Foxglove's) onto the sensor's x axis (its line of sight).
_Z_TO_X = fg.Quaternion(x=0.0, y=math.sqrt(0.5), z=0.0, w=math.sqrt(0.5))

BATTERY_SCHEMA = json_schema(
    "zendock.BatteryStatus",
    {
        "percentage": {"type": "number", "description": "state of charge, 0..1"},
        "voltage": {"type": ["number", "null"]},
        "current": {"type": ["number", "null"]},
        "charge": {"type": ["number", "null"]},
        "power_supply_status": {"type": "integer"},
        "status": {"type": "string"},
    },
)
RANGE_SCHEMA = json_schema(
    "zendock.Range",
    {
        "range": {"type": ["number", "null"], "description": "metres; null when nothing is in range"},
        "min_range": {"type": "number"},
        "max_range": {"type": "number"},
        "field_of_view": {"type": "number"},
    },
)
DOCK_CONTACT_SCHEMA = json_schema(
    "zendock.DockContact",
    {
        "dock_id": {"type": "string"},
        "mated": {"type": "boolean"},
        "touching": {"type": "boolean"},
        "lateral_error_m": {"type": "number"},
        "yaw_error_rad": {"type": "number"},
        "along_error_m": {"type": "number"},
    },
)
COLLISION_SCHEMA = json_schema(
    "zendock.CollisionEvent",
    {
        "kind": {"type": "string"},
        "count": {"type": "integer"},
        "x": {"type": "number"},
        "y": {"type": "number"},
    },
)

_BATTERY_STATUS_NAMES = {
    BatteryState.POWER_SUPPLY_STATUS_UNKNOWN: "unknown",
    BatteryState.POWER_SUPPLY_STATUS_CHARGING: "charging",
    BatteryState.POWER_SUPPLY_STATUS_DISCHARGING: "discharging",
    BatteryState.POWER_SUPPLY_STATUS_NOT_CHARGING: "not charging",
    BatteryState.POWER_SUPPLY_STATUS_FULL: "full",
}


def foxglove_pose(pose: Pose) -> fg.Pose:
    p, q = pose.position, pose.orientation
    return fg.Pose(
        position=fg.Vector3(x=p.x, y=p.y, z=p.z),
        orientation=fg.Quaternion(x=q.x, y=q.y, z=q.z, w=q.w),
    )


def frame_transforms(topic: str, msg: TFMessage) -> list[ViewMessage]:
    transforms = [
        fg.FrameTransform(
            timestamp=timestamp(t.header.stamp),
            parent_frame_id=t.header.frame_id,
            child_frame_id=t.child_frame_id,
            translation=fg.Vector3(
                x=t.transform.translation.x, y=t.transform.translation.y, z=t.transform.translation.z
            ),
            rotation=fg.Quaternion(
                x=t.transform.rotation.x,
                y=t.transform.rotation.y,
                z=t.transform.rotation.z,
                w=t.transform.rotation.w,
            ),
        )
        for t in msg.transforms
    ]
    stamp = stamp_ns(msg.transforms[-1].header.stamp) if msg.transforms else None
    return [protobuf_view(topic, fg.FrameTransforms(transforms=transforms), stamp)]


def laser_scan(topic: str, msg: LaserScan) -> list[ViewMessage]:
    ranges = np.asarray(msg.ranges, dtype=np.float64)
    ranges = np.where(np.isfinite(ranges), ranges, np.nan)
    scan = fg.LaserScan(
        timestamp=timestamp(msg.header.stamp),
        frame_id=msg.header.frame_id,
        pose=fg.Pose(position=fg.Vector3(), orientation=fg.Quaternion(w=1.0)),
        start_angle=msg.angle_min,
        end_angle=msg.angle_max,
        ranges=ranges.tolist(),
        intensities=np.asarray(msg.intensities, dtype=np.float64).tolist(),
    )
    return [protobuf_view(topic, scan, stamp_ns(msg.header.stamp))]


def range_cone_length_m(msg: Range) -> tuple[float, bool]:
    """How long to draw the cone, and whether it ends on an echo (else it spans the sensor's reach)."""
    if math.isfinite(msg.range) and msg.min_range <= msg.range <= msg.max_range:
        return msg.range, True
    if msg.range == -math.inf:
        return msg.min_range, True  # too close to measure: something is at the sensor's face
    return msg.max_range, False


def range_cone(topic: str, msg: Range) -> list[ViewMessage]:
    """The ultrasonic reading as its cone (apex at the sensor), plus the number for plots."""
    length_m, echo = range_cone_length_m(msg)
    length_m = max(length_m, 1e-3)
    diameter_m = 2.0 * length_m * math.tan(min(msg.field_of_view, 3.0) / 2.0)
    color = fg.Color(r=1.0, g=0.55, b=0.0, a=0.45) if echo else fg.Color(r=0.6, g=0.6, b=0.6, a=0.15)
    cone = fg.CylinderPrimitive(
        pose=fg.Pose(position=fg.Vector3(x=length_m / 2.0), orientation=_Z_TO_X),
        size=fg.Vector3(x=diameter_m, y=diameter_m, z=length_m),
        bottom_scale=0.0,
        top_scale=1.0,
        color=color,
    )
    stamp = stamp_ns(msg.header.stamp)
    entity = fg.SceneEntity(
        timestamp=timestamp(msg.header.stamp),
        frame_id=msg.header.frame_id,
        id="ultrasonic_cone",
        frame_locked=True,
        cylinders=[cone],
    )
    record = {
        "range": msg.range,
        "min_range": msg.min_range,
        "max_range": msg.max_range,
        "field_of_view": msg.field_of_view,
    }
    return [
        protobuf_view(topic, fg.SceneUpdate(entities=[entity]), stamp),
        json_view(f"{topic}/range", RANGE_SCHEMA, record, stamp),
    ]


def _map_colors(cells: np.ndarray) -> np.ndarray:
    """Occupancy -> RGBA: unknown clear, free pale, occupied dark, in between a grey ramp."""
    rgba = np.zeros((cells.size, 4), dtype=np.uint8)
    known = cells >= 0
    occ = np.clip(cells, 0, 100).astype(np.float64) / 100.0
    shade = (235.0 * (1.0 - occ)).astype(np.uint8)
    rgba[:, 0] = rgba[:, 1] = rgba[:, 2] = shade
    rgba[:, 3] = np.where(known, np.where(cells > 0, 230, 90), 0).astype(np.uint8)
    return rgba


def _cost_colors(cells: np.ndarray) -> np.ndarray:
    """Costmap cost (0..100) -> RGBA: free clear, rising cost from yellow to red, lethal purple."""
    rgba = np.zeros((cells.size, 4), dtype=np.uint8)
    cost = np.clip(cells, 0, 100).astype(np.float64) / 100.0
    rgba[:, 0] = 255
    rgba[:, 1] = (220.0 * (1.0 - cost)).astype(np.uint8)
    rgba[:, 2] = 0
    rgba[:, 3] = np.where(cells > 0, 60 + (120.0 * cost).astype(np.int64), 0).astype(np.uint8)
    lethal = cells >= 99
    rgba[lethal] = (150, 0, 200, 200)
    return rgba


def occupancy_grid(topic: str, msg: OccupancyGrid, costmap: bool = False) -> list[ViewMessage]:
    """An OccupancyGrid as a Grid: the cell value (int8) and RGBA colour fields Foxglove draws as they are."""
    info = msg.info
    cells = np.asarray(msg.data, dtype=np.int8)
    packed = np.zeros((cells.size, 5), dtype=np.uint8)
    packed[:, 0] = cells.view(np.uint8)
    packed[:, 1:] = _cost_colors(cells) if costmap else _map_colors(cells)
    fields = [
        fg.PackedElementField(
            name="cost" if costmap else "occupancy", offset=0, type=fg.PackedElementFieldNumericType.Int8
        ),
        fg.PackedElementField(name="red", offset=1, type=fg.PackedElementFieldNumericType.Uint8),
        fg.PackedElementField(name="green", offset=2, type=fg.PackedElementFieldNumericType.Uint8),
        fg.PackedElementField(name="blue", offset=3, type=fg.PackedElementFieldNumericType.Uint8),
        fg.PackedElementField(name="alpha", offset=4, type=fg.PackedElementFieldNumericType.Uint8),
    ]
    grid = fg.Grid(
        timestamp=timestamp(msg.header.stamp),
        frame_id=msg.header.frame_id or MAP_FRAME,
        pose=foxglove_pose(info.origin),
        column_count=int(info.width),
        cell_size=fg.Vector2(x=info.resolution, y=info.resolution),
        row_stride=int(info.width) * 5,
        cell_stride=5,
        fields=fields,
        data=packed.tobytes(),
    )
    return [protobuf_view(topic, grid, stamp_ns(msg.header.stamp))]


def costmap_grid(topic: str, msg: OccupancyGrid) -> list[ViewMessage]:
    return occupancy_grid(topic, msg, costmap=True)


def path_poses(topic: str, msg: Path) -> list[ViewMessage]:
    poses = fg.PosesInFrame(
        timestamp=timestamp(msg.header.stamp),
        frame_id=msg.header.frame_id or MAP_FRAME,
        poses=[foxglove_pose(p.pose) for p in msg.poses],
    )
    return [protobuf_view(topic, poses, stamp_ns(msg.header.stamp))]


def pose_stamped(topic: str, msg: PoseStamped) -> list[ViewMessage]:
    pose = fg.PoseInFrame(
        timestamp=timestamp(msg.header.stamp), frame_id=msg.header.frame_id, pose=foxglove_pose(msg.pose)
    )
    return [protobuf_view(topic, pose, stamp_ns(msg.header.stamp))]


#: What an on-demand image channel is advertised with before its first frame.
RAW_IMAGE_SCHEMA = protobuf_schema(fg.RawImage)


def raw_image(topic: str, msg: Image) -> list[ViewMessage]:
    """A camera frame as Foxglove's RawImage (mono8, rgb8, ... as they come: the same encodings)."""
    image = fg.RawImage(
        timestamp=timestamp(msg.header.stamp),
        frame_id=msg.header.frame_id,
        width=msg.width,
        height=msg.height,
        encoding=msg.encoding,
        step=msg.step,
        data=msg.data.tobytes(),
    )
    return [protobuf_view(topic, image, stamp_ns(msg.header.stamp))]


def pose2d_array(topic: str, msg: Float64MultiArray) -> list[ViewMessage]:
    """The localisation's ``[x, y, yaw]`` in the map frame (no stamp on the wire: the sink's clock)."""
    if len(msg.data) < 3:
        return []
    x, y, yaw = (float(v) for v in msg.data[:3])
    pose = fg.Pose(
        position=fg.Vector3(x=x, y=y),
        orientation=fg.Quaternion(z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0)),
    )
    return [protobuf_view(topic, fg.PoseInFrame(frame_id=MAP_FRAME, pose=pose))]


def battery_status(topic: str, msg: BatteryState) -> list[ViewMessage]:
    record = {
        "percentage": msg.percentage,
        "voltage": msg.voltage,
        "current": msg.current,
        "charge": msg.charge,
        "power_supply_status": msg.power_supply_status,
        "status": _BATTERY_STATUS_NAMES.get(msg.power_supply_status, "unknown"),
    }
    return [json_view(topic, BATTERY_SCHEMA, record, stamp_ns(msg.header.stamp))]


def dock_contact(topic: str, msg: DockContact) -> list[ViewMessage]:
    record = {
        "dock_id": msg.dock_id,
        "mated": msg.mated,
        "touching": msg.touching,
        "lateral_error_m": msg.lateral_error_m,
        "yaw_error_rad": msg.yaw_error_rad,
        "along_error_m": msg.along_error_m,
    }
    return [json_view(topic, DOCK_CONTACT_SCHEMA, record, stamp_ns(msg.header.stamp))]


def collision(topic: str, msg: CollisionEvent) -> list[ViewMessage]:
    record = {"kind": msg.kind, "count": msg.count, "x": msg.x, "y": msg.y}
    return [json_view(topic, COLLISION_SCHEMA, record, stamp_ns(msg.header.stamp))]
