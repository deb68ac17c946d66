"""zendock messages as Foxglove views: which key gets which view, and what the conversions keep."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from shared.foxglove_view import convert_key, robot_scene, staging_pose, view_for_key, view_topic, world_scene
from shared.foxglove_view.convert import range_cone_length_m
from shared.geometry import Pose2D
from shared.messages import (
    BatteryState,
    Header,
    Image,
    LaserScan,
    MapMetaData,
    OccupancyGrid,
    Range,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
    Twist,
)
from shared.world import load_world
from tests.support.processes import REPO_ROOT


def test_views_are_found_by_the_last_part_of_the_key() -> None:
    found = view_for_key("robot1/scan")
    assert found is not None and found[0].msg_type is LaserScan and found[1] == "robot1"
    assert view_for_key("cmd_vel") is None
    assert view_topic("robot1", "scan") == "/robot1/scan" and view_topic("", "tf") == "/tf"


def test_camera_frames_are_raw_images_under_their_two_part_topic() -> None:
    found = view_for_key("robot1/camera/image_raw")
    assert found is not None and found[0].on_demand and found[1] == "robot1"
    assert view_for_key("camera/image_raw") is not None and view_for_key("robot1/image_raw") is None
    pixels = np.arange(12, dtype=np.uint8)
    frame = Image(Header(Time(sec=3), "camera_optical_frame"), 3, 4, "mono8", 0, 4, pixels)
    views = convert_key("robot1/camera/image_raw", Image.TYPE_NAME, frame.encode())
    assert [v.topic for v in views] == ["/robot1/camera/image_raw"]
    assert views[0].schema.name == "foxglove.RawImage" and views[0].stamp_ns == 3_000_000_000
    assert pixels.tobytes() in views[0].data and b"mono8" in views[0].data


def test_a_payload_of_another_type_gets_no_view() -> None:
    assert convert_key("scan", Twist.TYPE_NAME, Twist().encode()) == []


def test_tf_keeps_its_stamp_and_frames() -> None:
    msg = TFMessage(
        [TransformStamped(Header(Time(12, 500), "map"), "odom", Transform.from_pose2d(Pose2D(1, 2, 0)))]
    )
    (view,) = convert_key("r/tf", msg.TYPE_NAME, msg.encode())
    assert view.topic == "/r/tf" and view.schema.name == "foxglove.FrameTransforms"
    assert view.schema.encoding == "protobuf" and view.stamp_ns == 12_000_000_500
    assert b"map" in view.data and b"odom" in view.data


def test_battery_is_json_with_unmeasured_values_as_null() -> None:
    msg = BatteryState(
        header=Header.at(3.0, "base_link"),
        percentage=0.75,
        power_supply_status=BatteryState.POWER_SUPPLY_STATUS_CHARGING,
    )
    (view,) = convert_key("battery_status", msg.TYPE_NAME, msg.encode())
    record = json.loads(view.data)
    assert record["percentage"] == 0.75 and record["voltage"] is None and record["status"] == "charging"
    assert view.schema.encoding == "jsonschema" and json.loads(view.schema.data)["title"] == view.schema.name


def test_the_map_grid_carries_occupancy_and_colours_per_cell() -> None:
    cells = np.array([-1, 0, 50, 100], dtype=np.int8)
    msg = OccupancyGrid(Header.at(1.0, "map"), MapMetaData(resolution=0.05, width=2, height=2), cells)
    (view,) = convert_key("map", msg.TYPE_NAME, msg.encode())
    assert view.schema.name == "foxglove.Grid"
    # five bytes a cell: the value, then red, green, blue, alpha (unknown clear, free pale, occupied dark)
    packed = bytes([255, 235, 235, 235, 0, 0, 235, 235, 235, 90, 50, 117, 117, 117, 230, 100, 0, 0, 0, 230])
    assert packed in view.data


def test_the_sonar_cone_ends_at_the_echo_or_spans_the_reach() -> None:
    def reading(value: float) -> Range:
        return Range(Header.at(0.0, "ultrasonic_link"), Range.ULTRASOUND, 0.5, 0.02, 3.0, value)

    assert range_cone_length_m(reading(1.2)) == (1.2, True)
    assert range_cone_length_m(reading(math.inf)) == (3.0, False)
    assert range_cone_length_m(reading(-math.inf)) == (0.02, True)
    cone, number = convert_key("ultrasonic", Range.TYPE_NAME, reading(1.2).encode())
    assert cone.schema.name == "foxglove.SceneUpdate" and b"ultrasonic_link" in cone.data
    assert number.topic == "/ultrasonic/range" and json.loads(number.data)["range"] == 1.2
    (_, far) = convert_key("ultrasonic", Range.TYPE_NAME, reading(math.inf).encode())
    assert json.loads(far.data)["range"] is None


def test_the_world_scene_has_walls_glass_dock_and_staging_pose() -> None:
    world = load_world(REPO_ROOT / "deploy/worlds/glass_room.yaml")
    scene = world_scene("/world", world, 5)
    for entity_id in (b"walls", b"glass", b"dock/home", b"staging/home"):
        assert entity_id in scene.data
    dock = world.dock("home").pose2d
    staging = staging_pose(dock, 0.7)
    assert staging.distance_to(dock) == pytest.approx(0.7)
    assert (staging.x, staging.y) == pytest.approx((dock.x, dock.y + 0.7))  # the dock faces -y: behind is +y
    assert b"base_link" in robot_scene("/robot").data
