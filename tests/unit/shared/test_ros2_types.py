"""zendock messages as ROS 2 Jazzy CDR: the bytes rosbags writes for the same message, and back."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from services.ros2_bridge.routes import INBOUND, OUTBOUND
from shared.messages import (
    BatteryState,
    CameraInfo,
    Clock,
    Float64MultiArray,
    Header,
    Image,
    LaserScan,
    MapMetaData,
    MultiArrayDimension,
    MultiArrayLayout,
    OccupancyGrid,
    Odometry,
    Path,
    Point,
    Pose,
    PoseStamped,
    PoseWithCovariance,
    Quaternion,
    Range,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
    Twist,
    TwistWithCovariance,
    Vector3,
)
from shared.ros2 import types
from shared.schema import Message

HEADER = Header(Time(12, 345_000_000), "base_link")
POSE = Pose(Point(1.5, -2.25, 0.0), Quaternion(0.0, 0.0, math.sin(0.3), math.cos(0.3)))

EXAMPLES: dict[str, Message] = {
    "rosgraph_msgs/msg/Clock": Clock(Time(99, 5)),
    "tf2_msgs/msg/TFMessage": TFMessage([
        TransformStamped(HEADER, "odom", Transform(Vector3(0.1, 0.2, 0.0), Quaternion(0.0, 0.0, 0.6, 0.8))),
        TransformStamped(Header(Time(1, 2), "map"), "base_link", Transform(Vector3(-3.0, 4.0, 0.5)))]),
    "nav_msgs/msg/Odometry": Odometry(HEADER, "base_link", PoseWithCovariance(POSE, np.arange(36.0)),
                                      TwistWithCovariance(Twist.planar(0.3, -0.7), np.full(36, 0.01))),
    "sensor_msgs/msg/LaserScan": LaserScan(HEADER, -3.1, 3.1, 0.0175, 0.0001, 0.1, 0.12, 12.0,
                                           np.array([1.0, math.inf, 0.5, -math.inf], dtype=np.float32),
                                           np.array([10.0, 0.0, 3.0, 1.0], dtype=np.float32)),
    "sensor_msgs/msg/Range": Range(HEADER, Range.ULTRASOUND, 0.26, 0.02, 4.0, 1.234),
    "sensor_msgs/msg/Image": Image(HEADER, 2, 3, "rgb8", 0, 9, np.arange(18, dtype=np.uint8)),
    "sensor_msgs/msg/CameraInfo": CameraInfo(HEADER, 480, 640, "plumb_bob", np.zeros(5),
                                             np.array([500.0, 0, 320, 0, 500, 240, 0, 0, 1]), np.eye(3).ravel(),
                                             np.arange(12.0)),
    "sensor_msgs/msg/BatteryState": BatteryState(HEADER, voltage=12.4, current=-0.4, charge=1.8, capacity=2.0,
                                                 design_capacity=2.0, percentage=0.9, power_supply_status=2,
                                                 power_supply_health=1, power_supply_technology=2,
                                                 cell_voltage=np.array([4.1, 4.2, 4.1], dtype=np.float32),
                                                 location="base_link", serial_number="zd-1"),
    "std_msgs/msg/Float64MultiArray": Float64MultiArray(
        MultiArrayLayout([MultiArrayDimension("pose", 3, 3)], 0), np.array([1.0, 2.0, 0.5])),
    "nav_msgs/msg/OccupancyGrid": OccupancyGrid(HEADER, MapMetaData(Time(3, 0), 0.05, 3, 2, POSE),
                                                np.array([0, 100, -1, 0, 0, 100], dtype=np.int8)),
    "nav_msgs/msg/Path": Path(Header(Time(5, 0), "map"), [PoseStamped(HEADER, POSE), PoseStamped(HEADER, Pose())]),
    "geometry_msgs/msg/PoseStamped": PoseStamped(Header(Time(7, 0), "map"), POSE),
    "geometry_msgs/msg/Twist": Twist(Vector3(0.25, 0.0, 0.0), Vector3(0.0, 0.0, -0.5)),
}


def _independent(value: Any, ros_type: str) -> Any:
    """The rosbags message built from zendock's msgpack map, field by field, without the converter."""
    store = types.typestore()
    cls = store.types[ros_type]
    _, fields = store.fielddefs[ros_type]
    wire = value.to_dict() if isinstance(value, Message) else value
    values: dict[str, Any] = {}
    for name, (kind, detail) in fields:
        given = wire.get(name) if wire is not None else None
        if kind == 2:
            values[name] = _independent(given, detail)
        elif kind == 1:
            values[name] = given if given is not None else ("" if detail[0] == "string" else 0)
        else:
            sub_kind, sub_detail = detail[0]
            if sub_kind == 2:
                values[name] = [_independent(item, sub_detail) for item in (given or [])]
            else:
                dtype = {"float32": np.float32, "float64": np.float64, "uint8": np.uint8, "int8": np.int8}[sub_detail[0]]
                raw = np.frombuffer(given, dtype=dtype) if isinstance(given, bytes) else np.array(given or [], dtype=dtype)
                values[name] = raw if kind == 4 or raw.size else np.zeros(detail[1], dtype=dtype)
    return cls(**values)


def test_every_bridged_type_has_an_example() -> None:
    assert {r.ros_type for r in OUTBOUND} | {"geometry_msgs/msg/Twist"} == set(EXAMPLES)


@pytest.mark.parametrize("ros_type", sorted(EXAMPLES))
def test_cdr_bytes_equal_rosbags_for_the_same_message(ros_type: str) -> None:
    msg = EXAMPLES[ros_type]
    ours = types.to_cdr(msg, ros_type)
    theirs = bytes(types.typestore().serialize_cdr(_independent(msg, ros_type), ros_type))
    assert ours[:4] == b"\x00\x01\x00\x00"  # CDR, little endian
    assert ours == theirs


@pytest.mark.parametrize("ros_type", sorted(EXAMPLES))
def test_cdr_reads_back_into_the_same_zendock_message(ros_type: str) -> None:
    msg = EXAMPLES[ros_type]
    back = types.from_ros(types.from_cdr(types.to_cdr(msg, ros_type), ros_type), type(msg))
    assert back.encode() == _float32_rounded(msg).encode()  # bytes: NaN equals NaN


def _float32_rounded(msg: Message) -> Message:
    """ROS 2 carries some fields as float32 (BatteryState, Range, LaserScan): compare what survives."""
    ros_type = msg.TYPE_NAME
    return types.from_ros(types.typestore().deserialize_cdr(
        types.typestore().serialize_cdr(_independent(msg, ros_type), ros_type), ros_type), type(msg))


def test_type_hashes_are_jazzys_published_values() -> None:
    assert types.type_hash("std_msgs/msg/String") == (
        "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18")
    assert types.type_hash("geometry_msgs/msg/Twist") == (
        "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a")
    for route in (*OUTBOUND, *INBOUND):
        assert types.type_hash(route.ros_type).startswith("RIHS01_") and len(types.type_hash(route.ros_type)) == 71


def test_unknown_types_and_bad_bytes_are_named() -> None:
    with pytest.raises(types.Ros2TypeError, match="not a ROS 2 Jazzy message type"):
        types.type_hash("zendock_msgs/msg/Nothing")
    good = types.to_cdr(EXAMPLES["sensor_msgs/msg/BatteryState"], "sensor_msgs/msg/BatteryState")
    with pytest.raises(types.Ros2TypeError, match="not CDR"):
        types.from_cdr(b"\x93\x01garbage", "geometry_msgs/msg/Twist")
    with pytest.raises(types.Ros2TypeError, match="malformed CDR"):
        types.from_cdr(good[:30], "sensor_msgs/msg/BatteryState")
    with pytest.raises(types.Ros2TypeError, match="malformed CDR"):
        types.from_cdr(b"\x00\x01\x00\x00\xff\xff\xff\x7f", "nav_msgs/msg/Path")
