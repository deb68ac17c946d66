"""ROS 2 message mirrors: same type names, same field names and nesting, carried as msgpack maps.

Constants keep their ROS names (``Range.ULTRASOUND``, ``BatteryState.POWER_SUPPLY_STATUS_CHARGING``).
Floats must be finite unless the ROS message gives NaN or infinity a meaning (unmeasured battery
values, out-of-range readings), where the field is :data:`~shared.schema.FloatAny`.
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import field
from typing import Annotated, ClassVar

import numpy as np

from shared.geometry import Pose2D, quaternion_from_yaw, yaw_from_quaternion
from shared.schema import (
    Float32Array,
    Float64Array,
    FloatAny,
    FloatAnyArray,
    Int8Array,
    Int32,
    Message,
    UInt8,
    UInt8Array,
    UInt32,
    message,
)
from shared.schema import (
    Range as Bounds,
)


def _zeros() -> np.ndarray:
    return np.zeros(0, dtype=np.float64)


def _zeros32() -> np.ndarray:
    return np.zeros(0, dtype=np.float32)


def _cov36() -> np.ndarray:
    return np.zeros(36, dtype=np.float64)


# --- builtin_interfaces / std_msgs ------------------------------------------------------------------


@message("builtin_interfaces/msg/Time")
class Time(Message):
    sec: Int32 = 0
    nanosec: Annotated[int, Bounds(0, 999_999_999)] = 0

    @classmethod
    def from_sec(cls, seconds: float) -> Time:
        whole = math.floor(seconds)
        nanos = int(round((seconds - whole) * 1e9))
        if nanos >= 1_000_000_000:
            whole, nanos = whole + 1, nanos - 1_000_000_000
        return cls(int(whole), nanos)

    def to_sec(self) -> float:
        return self.sec + self.nanosec * 1e-9


@message("builtin_interfaces/msg/Duration")
class Duration(Message):
    sec: Int32 = 0
    nanosec: Annotated[int, Bounds(0, 999_999_999)] = 0

    @classmethod
    def from_sec(cls, seconds: float) -> Duration:
        t = Time.from_sec(seconds)
        return cls(t.sec, t.nanosec)

    def to_sec(self) -> float:
        return self.sec + self.nanosec * 1e-9


@message("std_msgs/msg/Header")
class Header(Message):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""

    @classmethod
    def at(cls, seconds: float, frame_id: str) -> Header:
        return cls(Time.from_sec(seconds), frame_id)


@message("std_msgs/msg/Bool")
class Bool(Message):
    data: bool = False


@message("std_msgs/msg/String")
class String(Message):
    data: str = ""


@message("std_msgs/msg/Float64")
class Float64(Message):
    data: float = 0.0


@message("std_msgs/msg/MultiArrayDimension")
class MultiArrayDimension(Message):
    label: str = ""
    size: UInt32 = 0
    stride: UInt32 = 0


@message("std_msgs/msg/MultiArrayLayout")
class MultiArrayLayout(Message):
    dim: list[MultiArrayDimension] = field(default_factory=list)
    data_offset: UInt32 = 0


@message("std_msgs/msg/Float64MultiArray")
class Float64MultiArray(Message):
    """zendock sends only finite data on this type (the 2-D pose ``[x, y, yaw]``)."""

    layout: MultiArrayLayout = field(default_factory=MultiArrayLayout)
    data: Float64Array = field(default_factory=_zeros)


@message("rosgraph_msgs/msg/Clock")
class Clock(Message):
    clock: Time = field(default_factory=Time)


# --- geometry_msgs ----------------------------------------------------------------------------------


@message("geometry_msgs/msg/Vector3")
class Vector3(Message):
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@message("geometry_msgs/msg/Point")
class Point(Message):
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@message("geometry_msgs/msg/Quaternion")
class Quaternion(Message):
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    w: float = 1.0

    @classmethod
    def from_yaw(cls, yaw_rad: float) -> Quaternion:
        return cls(*quaternion_from_yaw(yaw_rad))

    def yaw(self) -> float:
        return yaw_from_quaternion(self.x, self.y, self.z, self.w)


@message("geometry_msgs/msg/Pose")
class Pose(Message):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)

    @classmethod
    def from_pose2d(cls, pose: Pose2D) -> Pose:
        return cls(Point(pose.x, pose.y, 0.0), Quaternion.from_yaw(pose.yaw))

    def to_pose2d(self) -> Pose2D:
        return Pose2D(self.position.x, self.position.y, self.orientation.yaw())


@message("geometry_msgs/msg/PoseStamped")
class PoseStamped(Message):
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@message("geometry_msgs/msg/PoseWithCovariance")
class PoseWithCovariance(Message):
    pose: Pose = field(default_factory=Pose)
    covariance: Float64Array = field(default_factory=_cov36)


@message("geometry_msgs/msg/PoseWithCovarianceStamped")
class PoseWithCovarianceStamped(Message):
    """What ``/initialpose`` carries (RViz's "2D Pose Estimate")."""

    header: Header = field(default_factory=Header)
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)


@message("geometry_msgs/msg/Twist")
class Twist(Message):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)

    @classmethod
    def planar(cls, linear_x: float, angular_z: float) -> Twist:
        return cls(Vector3(linear_x, 0.0, 0.0), Vector3(0.0, 0.0, angular_z))


@message("geometry_msgs/msg/TwistWithCovariance")
class TwistWithCovariance(Message):
    twist: Twist = field(default_factory=Twist)
    covariance: Float64Array = field(default_factory=_cov36)


@message("geometry_msgs/msg/Transform")
class Transform(Message):
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)

    @classmethod
    def from_pose2d(cls, pose: Pose2D) -> Transform:
        return cls(Vector3(pose.x, pose.y, 0.0), Quaternion.from_yaw(pose.yaw))

    def to_pose2d(self) -> Pose2D:
        return Pose2D(self.translation.x, self.translation.y, self.rotation.yaw())


@message("geometry_msgs/msg/TransformStamped")
class TransformStamped(Message):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@message("tf2_msgs/msg/TFMessage")
class TFMessage(Message):
    transforms: list[TransformStamped] = field(default_factory=list)


# --- nav_msgs ---------------------------------------------------------------------------------------


@message("nav_msgs/msg/Odometry")
class Odometry(Message):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@message("nav_msgs/msg/MapMetaData")
class MapMetaData(Message):
    map_load_time: Time = field(default_factory=Time)
    resolution: Annotated[float, Bounds(1e-6, 1e3)] = 0.05
    width: UInt32 = 0
    height: UInt32 = 0
    origin: Pose = field(default_factory=Pose)


@message("nav_msgs/msg/OccupancyGrid")
class OccupancyGrid(Message):
    """Row-major cells from the origin: -1 unknown, 0 free, 100 occupied."""

    header: Header = field(default_factory=Header)
    info: MapMetaData = field(default_factory=MapMetaData)
    data: Int8Array = field(default_factory=lambda: np.zeros(0, dtype=np.int8))


@message("nav_msgs/msg/Path")
class Path(Message):
    header: Header = field(default_factory=Header)
    poses: list[PoseStamped] = field(default_factory=list)


# --- sensor_msgs ------------------------------------------------------------------------------------


@message("sensor_msgs/msg/LaserScan")
class LaserScan(Message):
    """Ranges outside [range_min, range_max] are +inf (too far) or -inf (too close), as in REP 117."""

    header: Header = field(default_factory=Header)
    angle_min: float = 0.0
    angle_max: float = 0.0
    angle_increment: float = 0.0
    time_increment: float = 0.0
    scan_time: float = 0.0
    range_min: float = 0.0
    range_max: float = 0.0
    ranges: FloatAnyArray = field(default_factory=_zeros32)
    intensities: Float32Array = field(default_factory=_zeros32)


@message("sensor_msgs/msg/Range")
class Range(Message):
    ULTRASOUND: ClassVar[int] = 0
    INFRARED: ClassVar[int] = 1

    header: Header = field(default_factory=Header)
    radiation_type: Annotated[int, Bounds(0, 1)] = 0
    field_of_view: float = 0.0
    min_range: float = 0.0
    max_range: float = 0.0
    range: FloatAny = math.inf


@message("sensor_msgs/msg/BatteryState")
class BatteryState(Message):
    """``percentage`` is 0..1. NaN marks an unmeasured voltage, current, charge or capacity."""

    POWER_SUPPLY_STATUS_UNKNOWN: ClassVar[int] = 0
    POWER_SUPPLY_STATUS_CHARGING: ClassVar[int] = 1
    POWER_SUPPLY_STATUS_DISCHARGING: ClassVar[int] = 2
    POWER_SUPPLY_STATUS_NOT_CHARGING: ClassVar[int] = 3
    POWER_SUPPLY_STATUS_FULL: ClassVar[int] = 4
    POWER_SUPPLY_HEALTH_UNKNOWN: ClassVar[int] = 0
    POWER_SUPPLY_HEALTH_GOOD: ClassVar[int] = 1
    POWER_SUPPLY_TECHNOLOGY_UNKNOWN: ClassVar[int] = 0
    POWER_SUPPLY_TECHNOLOGY_LION: ClassVar[int] = 2

    header: Header = field(default_factory=Header)
    voltage: FloatAny = math.nan
    temperature: FloatAny = math.nan
    current: FloatAny = math.nan
    charge: FloatAny = math.nan
    capacity: FloatAny = math.nan
    design_capacity: FloatAny = math.nan
    percentage: Annotated[float, Bounds(0.0, 1.0)] = 0.0
    power_supply_status: Annotated[int, Bounds(0, 4)] = 0
    power_supply_health: Annotated[int, Bounds(0, 8)] = 0
    power_supply_technology: Annotated[int, Bounds(0, 6)] = 0
    present: bool = True
    cell_voltage: FloatAnyArray = field(default_factory=_zeros32)
    cell_temperature: FloatAnyArray = field(default_factory=_zeros32)
    location: str = ""
    serial_number: str = ""


@message("sensor_msgs/msg/Image")
class Image(Message):
    """An uncompressed image: ``height`` rows of ``step`` bytes (``mono8``: one byte a pixel; ``rgb8``: three)."""

    header: Header = field(default_factory=Header)
    height: UInt32 = 0
    width: UInt32 = 0
    encoding: str = ""
    is_bigendian: UInt8 = 0
    step: UInt32 = 0
    data: UInt8Array = field(default_factory=lambda: np.zeros(0, dtype=np.uint8))


@message("sensor_msgs/msg/RegionOfInterest")
class RegionOfInterest(Message):
    x_offset: UInt32 = 0
    y_offset: UInt32 = 0
    height: UInt32 = 0
    width: UInt32 = 0
    do_rectify: bool = False


@message("sensor_msgs/msg/CameraInfo")
class CameraInfo(Message):
    """A pinhole camera's calibration, as ROS 2 gives it: ``k`` (3x3), ``r`` (3x3), ``p`` (3x4) row-major."""

    header: Header = field(default_factory=Header)
    height: UInt32 = 0
    width: UInt32 = 0
    distortion_model: str = ""
    d: Float64Array = field(default_factory=_zeros)
    k: Float64Array = field(default_factory=lambda: np.zeros(9))
    r: Float64Array = field(default_factory=lambda: np.zeros(9))
    p: Float64Array = field(default_factory=lambda: np.zeros(12))
    binning_x: UInt32 = 0
    binning_y: UInt32 = 0
    roi: RegionOfInterest = field(default_factory=RegionOfInterest)


# --- zendock's own -------------------------------------------------------------------------------


@message("zendock_msgs/msg/DockContact")
class DockContact(Message):
    """The simulator's ground truth about the robot's charging contacts.

    ``mated``: the contacts touch a dock's charging plate within the alignment tolerances. The errors are
    the robot's base_link relative to the nearest dock pose (lateral and yaw as docked; along: distance
    still to go), so reports judge docking precision on ground truth, not on the robot's belief.
    """

    header: Header = field(default_factory=Header)
    dock_id: str = ""
    mated: bool = False
    touching: bool = False
    lateral_error_m: float = 0.0
    yaw_error_rad: float = 0.0
    along_error_m: float = 0.0


@message("zendock_msgs/msg/CollisionEvent")
class CollisionEvent(Message):
    """One collision: the robot began touching something it should not. ``count`` is the total so far;
    ``other_robot`` names the robot it touched when ``kind`` is "robot" (robots sharing a room)."""

    header: Header = field(default_factory=Header)
    kind: str = ""  # wall | glass | box | dock | robot
    count: UInt32 = 0
    x: float = 0.0
    y: float = 0.0
    other_robot: str = ""


@message("zendock_msgs/msg/PacingHold")
class PacingHold(Message):
    """A robot standing for its controllers, for a simulator that paces itself by its drivers.

    While a robot moves, the world waits for the command of each of its controller's ticks; a robot
    standing still is waited for by nobody. It stands between two drivers (the docking service has sent
    the planner a goal, or has cancelled the planner's goal and waits for it to end before it drives), and
    while a driver works before it can drive on (the planner's plan after a stop, a costmap change). A
    hold (``hold`` true) says: from ``header.stamp`` (the sim time of the tick the ``holder`` decided on),
    do not run the world on until the holder lets go (``hold`` false) or, with ``until_driven``, until a
    command that moves the robot answers that tick or a later one (the next driver has taken over; a hold
    arriving after such a command is stale and ignored). The simulator waits, while nothing but holds is
    late, up to its budget for a hold (``pacing.hold_wait_max_s``).
    """

    header: Header = field(default_factory=Header)
    holder: str = ""
    hold: bool = True
    until_driven: bool = True


@message("zendock_msgs/msg/DockDetection")
class DockDetection(Message):
    """A dock found by its marker: its pose (the docked base_link pose) in ``header.frame_id``, and how well.

    ``reprojection_error_px`` is the RMS distance between the marker's detected corners and the corners of
    the chosen pose reprojected; ``marker_range_m`` is the camera-to-marker distance.
    """

    header: Header = field(default_factory=Header)
    dock_id: str = ""
    marker_id: UInt32 = 0
    pose: Pose = field(default_factory=Pose)
    reprojection_error_px: float = 0.0
    marker_range_m: float = 0.0


@message("kobuki_ros_interfaces/msg/DockInfraRed")
class DockInfraRed(Message):
    """What the robot's infrared receivers see of the dock's beacon: ``data`` is ``[right, central, left]``,
    each a bit field of the constants below (Kobuki's message, field for field)."""

    NEAR_LEFT: ClassVar[int] = 1
    NEAR_CENTER: ClassVar[int] = 2
    NEAR_RIGHT: ClassVar[int] = 4
    FAR_CENTER: ClassVar[int] = 8
    FAR_LEFT: ClassVar[int] = 16
    FAR_RIGHT: ClassVar[int] = 32

    header: Header = field(default_factory=Header)
    data: UInt8Array = field(default_factory=lambda: np.zeros(3, dtype=np.uint8))


def now_header(frame_id: str, seconds: float | None = None) -> Header:
    """A header stamped ``seconds`` (wall clock when omitted)."""
    return Header.at(_time.time() if seconds is None else seconds, frame_id)


__all__ = [
    "BatteryState",
    "Bool",
    "CameraInfo",
    "Clock",
    "CollisionEvent",
    "DockContact",
    "DockDetection",
    "DockInfraRed",
    "Duration",
    "Float64",
    "Image",
    "RegionOfInterest",
    "Float64MultiArray",
    "Header",
    "LaserScan",
    "MapMetaData",
    "MultiArrayDimension",
    "MultiArrayLayout",
    "OccupancyGrid",
    "Odometry",
    "PacingHold",
    "Path",
    "Point",
    "Pose",
    "PoseStamped",
    "PoseWithCovariance",
    "Quaternion",
    "Range",
    "String",
    "TFMessage",
    "Time",
    "Transform",
    "TransformStamped",
    "Twist",
    "TwistWithCovariance",
    "UInt8",
    "Vector3",
    "now_header",
]
