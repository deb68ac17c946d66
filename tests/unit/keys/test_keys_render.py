"""YAML-like, CSV, field and hex output of echoed messages."""

from __future__ import annotations

import io
import math

import msgpack
import pytest
import yaml

from deploy.keys.decoding import decode_payload
from deploy.keys.render import (
    EchoFormat,
    FieldNotFound,
    csv_row,
    flow_text,
    format_flow_list,
    format_scalar,
    format_string,
    sample_lines,
    select_field,
    write_sample,
    yaml_lines,
)
from shared.messages import Header, Path, PoseStamped, Time, Twist

TWIST_ENC = "application/msgpack;geometry_msgs/msg/Twist"


def test_twist_prints_like_ros2_topic_echo() -> None:
    out = io.StringIO()
    write_sample(out, decode_payload("k", Twist.planar(0.2, 0.0).encode(), TWIST_ENC), EchoFormat())
    assert out.getvalue() == (
        "linear:\n  x: 0.2\n  y: 0.0\n  z: 0.0\nangular:\n  x: 0.0\n  y: 0.0\n  z: 0.0\n---\n"
    )


def test_lists_of_messages_are_block_items_and_output_is_yaml() -> None:
    path = Path(Header(Time(3, 5), "map"), [PoseStamped(), PoseStamped()])
    text = "\n".join(
        yaml_lines(decode_payload("p", path.encode(), "application/msgpack;nav_msgs/msg/Path").value)
    )
    assert "poses:\n- header:\n    stamp:\n      sec: 0" in text
    assert yaml.safe_load(text)["poses"][1]["pose"]["orientation"]["w"] == 1.0
    assert yaml.safe_load(text)["header"]["frame_id"] == "map"


def test_scalars_use_yaml_spelling() -> None:
    assert [format_scalar(v) for v in (math.nan, math.inf, -math.inf, True, None, 3, 0.1)] == [
        ".nan",
        ".inf",
        "-.inf",
        "true",
        "null",
        "3",
        "0.1",
    ]
    assert format_scalar(b"\x01\x02") == "<2 bytes: 0102>"


@pytest.mark.parametrize(
    "text", ["base_link", "", "true", "1.5", "a: b", "#x", " lead", "it's", "two\nlines", "é"]
)
def test_strings_read_back_as_the_same_string(text: str) -> None:
    assert yaml.safe_load(f"k: {format_string(text)}")["k"] == text


def test_long_arrays_are_compact_and_truncated() -> None:
    assert format_flow_list([1.0, 2.0], 16) == "[1.0, 2.0]"
    assert format_flow_list(list(range(20)), 3) == "[0, 1, 2, ... +17 more (20 items)]"
    assert format_flow_list(list(range(20)), 0).count(",") == 19
    assert yaml_lines({"ranges": [0.5] * 360, "empty": []}, 2) == [
        "ranges: [0.5, 0.5, ... +358 more (360 items)]",
        "empty: []",
    ]


def test_select_field_by_dotted_path_and_index() -> None:
    tree = {"poses": [{"x": 1}, {"x": 2}], "data": [10, 20, 30], "header": {"frame_id": "map"}}
    assert select_field(tree, "poses.1.x") == 2
    assert select_field(tree, "poses[0].x") == 1
    assert select_field(tree, "data.-1") == 30
    assert select_field(tree, "header") == {"frame_id": "map"}
    for bad, reason in [
        ("nope", "no field 'nope'"),
        ("data.7", "out of range"),
        ("data.x", "expected an index"),
        ("header.frame_id.z", "has no field 'z'"),
        ("", "names no field"),
    ]:
        with pytest.raises(FieldNotFound, match=reason):
            select_field(tree, bad)


def test_csv_row_holds_every_leaf_in_order() -> None:
    assert csv_row({"a": {"x": 0.5, "y": -1}, "b": [1, 2], "s": "x,y", "ok": True}) == '0.5,-1,1,2,"x,y",true'


def test_field_missing_from_a_valid_message_is_the_users_mistake() -> None:
    sample = decode_payload("k", Twist().encode(), TWIST_ENC)
    assert sample_lines(sample, EchoFormat(field="linear.x")) == ["0.0"]
    with pytest.raises(FieldNotFound, match="no field 'q' in linear"):
        sample_lines(sample, EchoFormat(field="linear.q"))
    # on a wildcard, other keys may carry other types: a note, not an error
    assert sample_lines(sample, EchoFormat(field="header", strict_field=False)) == [
        "# --field header: no field 'header' in the message (fields: linear, angular)"
    ]


def test_bad_payloads_become_notes_in_every_format() -> None:
    garbage = decode_payload("k", b"\xc1\xc1", TWIST_ENC)
    assert sample_lines(garbage, EchoFormat()) == ["<2 bytes, not msgpack: c1c1>"]
    assert sample_lines(garbage, EchoFormat(csv=True)) == ["# <2 bytes, not msgpack: c1c1>"]
    assert sample_lines(garbage, EchoFormat(raw=True)) == ["c1c1"]
    wrong = decode_payload("k", msgpack.packb({"speed": 1}), TWIST_ENC)
    lines = sample_lines(wrong, EchoFormat(field="linear.x"))
    assert lines[0].startswith("# not a valid geometry_msgs/msg/Twist") and "no field 'linear'" in lines[1]


def test_key_and_sequence_header() -> None:
    sample = decode_payload("r/cmd_vel", Twist().encode(), TWIST_ENC, sequence=42)
    lines = sample_lines(sample, EchoFormat(show_key=True, show_sequence=True, csv=True))
    assert lines == ["# r/cmd_vel [geometry_msgs/msg/Twist] seq 42", "0.0,0.0,0.0,0.0,0.0,0.0"]


def test_csv_has_no_separator_lines() -> None:
    out = io.StringIO()
    write_sample(out, decode_payload("k", Twist().encode(), TWIST_ENC), EchoFormat(csv=True))
    assert out.getvalue() == "0.0,0.0,0.0,0.0,0.0,0.0\n"


def test_flow_text_is_one_line() -> None:
    assert flow_text({"linear": {"x": 0.2}, "names": ["a", "b"], "l": [{"k": 1}]}) == (
        "{linear: {x: 0.2}, names: [a, b], l: [{k: 1}]}"
    )
