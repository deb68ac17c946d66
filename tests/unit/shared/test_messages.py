"""Messages: exact ROS field layout, round trips, and every kind of validation error."""

from __future__ import annotations

import math

import msgpack
import numpy as np
import pytest

from shared.geometry import Pose2D
from shared.messages import (
    BatteryState,
    Bool,
    Clock,
    Float64MultiArray,
    Header,
    LaserScan,
    OccupancyGrid,
    Odometry,
    Path,
    Pose,
    PoseStamped,
    Range,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
    Twist,
)
from shared.schema import MessageError, message_type, registered_types


def test_twist_wire_layout_mirrors_ros() -> None:
    wire = msgpack.unpackb(Twist.planar(0.5, -0.2).encode())
    assert wire == {"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": -0.2}}


def test_header_and_multiarray_layout() -> None:
    header = msgpack.unpackb(Header.at(12.25, "map").encode())
    assert header == {"stamp": {"sec": 12, "nanosec": 250_000_000}, "frame_id": "map"}
    arr = msgpack.unpackb(Float64MultiArray(data=np.array([1.0, 2.0, 0.5])).encode())
    assert arr == {"layout": {"dim": [], "data_offset": 0}, "data": [1.0, 2.0, 0.5]}


def test_constants_keep_ros_values() -> None:
    assert (Range.ULTRASOUND, Range.INFRARED) == (0, 1)
    assert [
        BatteryState.POWER_SUPPLY_STATUS_UNKNOWN,
        BatteryState.POWER_SUPPLY_STATUS_CHARGING,
        BatteryState.POWER_SUPPLY_STATUS_DISCHARGING,
        BatteryState.POWER_SUPPLY_STATUS_NOT_CHARGING,
        BatteryState.POWER_SUPPLY_STATUS_FULL,
    ] == [0, 1, 2, 3, 4]


@pytest.mark.parametrize(
    "msg",
    [
        Twist.planar(0.3, 1.0),
        Header.at(3.5, "odom"),
        Clock(Time(5, 10)),
        Bool(True),
        PoseStamped(Header.at(1.0, "map"), Pose.from_pose2d(Pose2D(1.0, -2.0, 0.7))),
        TFMessage(
            [TransformStamped(Header.at(2.0, "odom"), "base_link", Transform.from_pose2d(Pose2D(1, 2, 3)))]
        ),
        Odometry(Header.at(1.0, "odom"), "base_link"),
        Path(Header.at(0.0, "map"), [PoseStamped(), PoseStamped()]),
        BatteryState(percentage=0.3, power_supply_status=BatteryState.POWER_SUPPLY_STATUS_DISCHARGING),
        Range(
            radiation_type=Range.ULTRASOUND, field_of_view=0.5, min_range=0.02, max_range=3.0, range=math.inf
        ),
    ],
    ids=lambda m: type(m).__name__,
)
def test_round_trip(msg) -> None:  # type: ignore[no-untyped-def]
    again = type(msg).decode(msg.encode())
    assert again.encode() == msg.encode()  # byte-identical (NaN compares unequal as a float)


def test_arrays_round_trip_as_numpy() -> None:
    scan = LaserScan(
        ranges=np.array([1.0, np.inf, 2.5], dtype=np.float32), intensities=np.zeros(3, np.float32)
    )
    back = LaserScan.decode(scan.encode())
    assert back.ranges.dtype == np.float32
    assert np.isinf(back.ranges[1]) and back.ranges[2] == pytest.approx(2.5)
    grid = OccupancyGrid(data=np.array([-1, 0, 100] * 100, dtype=np.int8))
    assert np.array_equal(OccupancyGrid.decode(grid.encode()).data, grid.data)


def test_plain_int_list_accepted_for_grid_data() -> None:
    wire = OccupancyGrid().to_dict()
    wire["data"] = [0, 100, -1]
    assert OccupancyGrid.from_dict(wire).data.tolist() == [0, 100, -1]


def test_time_from_sec_carries_rounding() -> None:
    t = Time.from_sec(1.9999999999)
    assert (t.sec, t.nanosec) == (2, 0)
    assert Time.from_sec(-0.5).to_sec() == pytest.approx(-0.5)


def _error(fn) -> MessageError:  # type: ignore[no-untyped-def]
    with pytest.raises(MessageError) as info:
        fn()
    return info.value


def test_garbage_payload() -> None:
    err = _error(lambda: Twist.decode(b"\xc1\x00\xff"))
    assert "not valid msgpack" in str(err) and err.type_name == "geometry_msgs/msg/Twist"


def test_not_a_map() -> None:
    err = _error(lambda: Twist.decode(msgpack.packb([1, 2, 3])))
    assert "expected a map" in str(err)


def test_missing_field_named_with_path() -> None:
    err = _error(
        lambda: Twist.from_dict({"linear": {"x": 1.0, "y": 0.0}, "angular": {"x": 0, "y": 0, "z": 0}})
    )
    assert err.field == "linear.z" and "missing" in err.reason


def test_unknown_field() -> None:
    wire = Bool(True).to_dict() | {"extra": 1}
    err = _error(lambda: Bool.from_dict(wire))
    assert err.field == "extra" and "unknown field" in err.reason


def test_wrong_type() -> None:
    err = _error(
        lambda: Twist.from_dict(
            {"linear": {"x": "fast", "y": 0, "z": 0}, "angular": {"x": 0, "y": 0, "z": 0}}
        )
    )
    assert err.field == "linear.x" and "expected a number" in err.reason
    err = _error(lambda: Bool.from_dict({"data": 1}))
    assert "true or false" in err.reason


def test_nan_refused_where_not_allowed_but_kept_where_ros_allows() -> None:
    err = _error(lambda: Twist.planar(math.nan, 0.0).encode())
    assert err.field == "linear.x" and "finite" in err.reason
    state = BatteryState(percentage=0.5)
    assert math.isnan(BatteryState.decode(state.encode()).voltage)


def test_enum_and_range_bounds() -> None:
    wire = BatteryState(percentage=0.5).to_dict() | {"power_supply_status": 7}
    err = _error(lambda: BatteryState.from_dict(wire))
    assert err.field == "power_supply_status" and "[0, 4]" in err.reason
    err = _error(lambda: BatteryState(percentage=1.5).encode())
    assert err.field == "percentage"
    err = _error(lambda: Range(radiation_type=3).encode())
    assert err.field == "radiation_type"


def test_array_errors() -> None:
    err = _error(
        lambda: Float64MultiArray.from_dict({"layout": {"dim": [], "data_offset": 0}, "data": [1.0, "x"]})
    )
    assert err.field == "data" and "numbers" in err.reason
    err = _error(lambda: Float64MultiArray(data=np.array([1.0, np.nan])).encode())
    assert "finite" in err.reason
    err = _error(lambda: OccupancyGrid.from_dict(OccupancyGrid().to_dict() | {"data": [0, 300]}))
    assert "[-128, 127]" in err.reason


def test_nested_list_error_path() -> None:
    wire = TFMessage([TransformStamped(), TransformStamped()]).to_dict()
    wire["transforms"][1]["transform"]["rotation"]["w"] = None
    err = _error(lambda: TFMessage.from_dict(wire))
    assert err.field == "transforms[1].transform.rotation.w"


def test_error_names_key_when_given() -> None:
    err = _error(lambda: Twist.decode(b"\x01"))
    err.at(key="robot1/cmd_vel")
    assert str(err).startswith("robot1/cmd_vel: geometry_msgs/msg/Twist:")


def test_registry_knows_every_required_type() -> None:
    required = {
        "std_msgs/msg/Header",
        "builtin_interfaces/msg/Time",
        "geometry_msgs/msg/Twist",
        "geometry_msgs/msg/Pose",
        "geometry_msgs/msg/PoseStamped",
        "geometry_msgs/msg/Transform",
        "geometry_msgs/msg/TransformStamped",
        "tf2_msgs/msg/TFMessage",
        "nav_msgs/msg/Odometry",
        "sensor_msgs/msg/LaserScan",
        "sensor_msgs/msg/Range",
        "sensor_msgs/msg/BatteryState",
        "rosgraph_msgs/msg/Clock",
        "std_msgs/msg/Float64MultiArray",
        "std_msgs/msg/Bool",
    }
    assert required <= set(registered_types())
    assert message_type("geometry_msgs/msg/Twist") is Twist


def test_empty_arrays_round_trip_with_their_type() -> None:
    grid = OccupancyGrid.from_dict(OccupancyGrid().to_dict() | {"data": []})
    assert grid.data.dtype == np.int8 and grid.data.size == 0
    assert OccupancyGrid.decode(OccupancyGrid().encode()).data.size == 0
