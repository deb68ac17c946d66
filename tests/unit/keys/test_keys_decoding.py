"""Decoding for display never raises: valid, wrong-shape, unknown-type and non-msgpack payloads."""

from __future__ import annotations

import math

import msgpack
import numpy as np

from deploy.keys.decoding import decode_payload, message_tree, undecodable_note
from deploy.keys.types import known_types
from shared.interface_types import GoalStatusArray
from shared.messages import BatteryState, LaserScan, OccupancyGrid, Twist

TWIST_ENC = "application/msgpack;geometry_msgs/msg/Twist"


def test_registered_type_decodes_in_field_order() -> None:
    sample = decode_payload("r/cmd_vel", Twist.planar(0.2, -0.1).encode(), TWIST_ENC, sequence=7)
    assert sample.message == Twist.planar(0.2, -0.1)
    assert list(sample.value) == ["linear", "angular"]
    assert sample.value["angular"]["z"] == -0.1
    assert (sample.note, sample.undecodable, sample.invalid, sample.sequence) == ("", False, False, 7)
    assert sample.type_label == "geometry_msgs/msg/Twist"


def test_garbage_bytes_become_a_note_with_hex() -> None:
    payload = b"\x0a\x0b\xc1\xff"
    sample = decode_payload("r/cmd_vel", payload, TWIST_ENC)
    assert sample.undecodable and sample.message is None
    assert sample.note == "<4 bytes, not msgpack: 0a0bc1ff>"


def test_long_garbage_is_previewed_not_dumped() -> None:
    note = undecodable_note(bytes([0xC1]) * 100)
    assert note.startswith("<100 bytes, not msgpack: c1c1") and note.endswith("...>")
    assert len(note) < 120


def test_msgpack_of_the_wrong_shape_is_shown_plain_with_the_reason() -> None:
    payload = msgpack.packb({"linear": {"x": "fast"}, "angular": {}})
    sample = decode_payload("r/cmd_vel", payload, TWIST_ENC)
    assert sample.invalid and not sample.undecodable and sample.message is None
    assert sample.value == {"linear": {"x": "fast"}, "angular": {}}
    assert "not a valid geometry_msgs/msg/Twist" in sample.note and "linear" in sample.note


def test_unknown_type_and_no_type_fall_back_to_plain_msgpack() -> None:
    payload = msgpack.packb({"a": [1, 2], 3: b"\x00\x01"})
    unknown = decode_payload("k", payload, "application/msgpack;other_msgs/msg/Thing")
    assert unknown.value == {"a": [1, 2], 3: b"\x00\x01"} and "not known" in unknown.note
    assert not unknown.invalid
    untyped = decode_payload("k", payload, "")
    assert untyped.value == unknown.value and untyped.note == "" and untyped.type_label == "no type"


def test_text_payloads_are_shown_as_text() -> None:
    sample = decode_payload("k", "héllo".encode(), "text/plain")
    assert sample.value == "héllo" and not sample.undecodable


def test_nil_payload_is_a_value_not_garbage() -> None:
    sample = decode_payload("k", msgpack.packb(None), "")
    assert sample.value is None and not sample.undecodable


def test_arrays_become_short_float_lists_and_nan_survives() -> None:
    scan = LaserScan(ranges=np.array([0.1, math.inf, 2.5], dtype=np.float32))
    tree = message_tree(scan)
    assert tree["ranges"] == [0.1, math.inf, 2.5]  # float32 0.1 printed as 0.1, not 0.10000000149011612
    battery = message_tree(BatteryState())
    assert math.isnan(battery["voltage"])
    grid = OccupancyGrid(data=np.full(100, -1, dtype=np.int8))  # travels as bytes, shown as numbers
    decoded = decode_payload("map", grid.encode(), "application/msgpack;nav_msgs/msg/OccupancyGrid")
    assert decoded.value["data"] == [-1] * 100


def test_action_and_service_interface_types_are_known() -> None:
    sample = decode_payload(
        "r/dock_robot/_action/status",
        GoalStatusArray().encode(),
        "application/msgpack;action_msgs/msg/GoalStatusArray",
    )
    assert sample.note == "" and sample.value == {"status_list": []}
    assert "opennav_docking_msgs/action/DockRobot_Goal" in known_types()
