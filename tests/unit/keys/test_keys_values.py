"""Building a message from YAML: merged over defaults, validated, errors naming the field."""

from __future__ import annotations

import math

import pytest

from deploy.keys import values
from deploy.keys.errors import EXIT_USAGE, KeysError
from deploy.keys.values import build_message, message_factory, parse_yaml_values, resolve_type
from shared.messages import BatteryState, Path, PoseStamped, String, TFMessage, Twist


@pytest.mark.parametrize("text", ["geometry_msgs/msg/Twist", "geometry_msgs/Twist", "Twist", " Twist "])
def test_type_names_in_full_short_and_bare_forms(text: str) -> None:
    assert resolve_type(text) is Twist


def test_unknown_type_suggests_close_names() -> None:
    with pytest.raises(KeysError, match="did you mean geometry_msgs/msg/Twist") as error:
        resolve_type("geometry_msgs/msg/Twst")
    assert error.value.exit_code == EXIT_USAGE


def test_bare_name_shared_by_several_types_is_ambiguous(monkeypatch: pytest.MonkeyPatch) -> None:
    assert resolve_type("Range").TYPE_NAME == "sensor_msgs/msg/Range"
    two_twists = {"geometry_msgs/msg/Twist": Twist, "other_msgs/msg/Twist": Twist}
    monkeypatch.setattr(values, "known_types", lambda: two_twists)
    with pytest.raises(KeysError, match="ambiguous: geometry_msgs/msg/Twist, other_msgs/msg/Twist"):
        resolve_type("Twist")
    with pytest.raises(KeysError, match="unknown message type"):
        resolve_type("NoSuchThing")


def test_partial_yaml_is_merged_over_defaults() -> None:
    msg = build_message(Twist, parse_yaml_values("{linear: {x: 0.2}}"))
    assert msg == Twist.planar(0.2, 0.0)
    assert build_message(String, parse_yaml_values("")) == String("")


def test_list_items_that_are_messages_get_their_defaults() -> None:
    msg = build_message(
        Path, {"header": {"frame_id": "map"}, "poses": [{"pose": {"position": {"x": 1}}}, {}]}
    )
    assert isinstance(msg, Path) and len(msg.poses) == 2
    assert msg.poses[0].pose.position.x == 1.0 and msg.poses[0].pose.orientation.w == 1.0
    assert msg.poses[1] == PoseStamped()


def test_now_and_auto_stamp_each_message() -> None:
    make = message_factory(BatteryState, {"header": "auto", "percentage": 0.5})
    first, second = make(100.25), make(101.5)
    assert isinstance(first, BatteryState) and isinstance(second, BatteryState)
    assert first.header.stamp.to_sec() == pytest.approx(100.25) and first.header.frame_id == ""
    assert second.header.stamp.to_sec() == pytest.approx(101.5)
    assert math.isnan(first.voltage)  # the default survives the merge
    tf = build_message(
        TFMessage, {"transforms": [{"header": {"stamp": "now", "frame_id": "odom"}}]}, now_s=7.5
    )
    assert isinstance(tf, TFMessage) and tf.transforms[0].header.stamp.to_sec() == 7.5


@pytest.mark.parametrize(
    ("values", "field", "reason"),
    [
        ({"linear": {"q": 1}}, "linear.q", "unknown field"),
        ({"speed": 1}, "speed", "unknown field"),
        ({"linear": {"x": "fast"}}, "linear.x", "expected a number"),
        ({"linear": 3}, "linear", "expected a map"),
        ({"angular": {"z": float("inf")}}, "angular.z", "must be finite"),
    ],
)
def test_bad_values_name_the_field(values: dict, field: str, reason: str) -> None:
    with pytest.raises(KeysError) as error:
        build_message(Twist, values)
    assert error.value.exit_code == EXIT_USAGE
    assert f"field '{field}'" in str(error.value) and reason in str(error.value)


def test_out_of_range_values_are_refused() -> None:
    with pytest.raises(KeysError, match=r"field 'percentage'.*within"):
        build_message(BatteryState, {"percentage": 1.5})


def test_factory_validates_before_anything_is_built() -> None:
    with pytest.raises(KeysError, match="linear.x"):
        message_factory(Twist, {"linear": {"x": "fast"}})


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("{linear: [", "not valid YAML"),
        ("[1, 2]", "must be a YAML mapping"),
        ("0.5", "must be a YAML mapping"),
    ],
)
def test_yaml_that_is_not_a_mapping_is_refused(text: str, reason: str) -> None:
    with pytest.raises(KeysError, match=reason) as error:
        parse_yaml_values(text)
    assert error.value.exit_code == EXIT_USAGE


def test_empty_yaml_means_defaults() -> None:
    assert parse_yaml_values("") == {} and parse_yaml_values("  ") == {} and parse_yaml_values("~") == {}
