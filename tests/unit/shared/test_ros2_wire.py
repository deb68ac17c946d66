"""rmw_zenoh's wire forms: type names, data keys, graph tokens, QoS strings and attachments."""

from __future__ import annotations

import pytest

from shared.ros2.wire import (
    LATCHED,
    RELIABLE,
    SENSOR_DATA,
    Attachment,
    Durability,
    Endpoint,
    EntityKind,
    GraphNode,
    QosProfile,
    Reliability,
    data_key,
    dds_type_name,
    demangle,
    mangle,
    parse_endpoint_token,
    qualified_name,
    ros_type_name,
)

HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"


def test_type_names_follow_rosidl() -> None:
    assert dds_type_name("sensor_msgs/msg/BatteryState") == "sensor_msgs::msg::dds_::BatteryState_"
    assert ros_type_name("sensor_msgs::msg::dds_::BatteryState_") == "sensor_msgs/msg/BatteryState"
    with pytest.raises(ValueError, match="package/msg/Name"):
        dds_type_name("BatteryState")
    with pytest.raises(ValueError, match="not a DDS type name"):
        ros_type_name("sensor_msgs::msg::BatteryState")


def test_names_mangle_into_one_key_chunk() -> None:
    assert mangle("/") == "%" and mangle("") == "%"
    assert mangle("/robot/scan") == "%robot%scan"
    assert demangle("%robot%scan") == "/robot/scan" and demangle("%") == "/"
    assert qualified_name("/", "scan") == "/scan"
    assert qualified_name("/robot", "camera/image_raw") == "/robot/camera/image_raw"
    assert qualified_name("robot/", "/clock") == "/clock"


def test_data_key_is_domain_topic_type_hash() -> None:
    assert data_key(3, "/chatter", "std_msgs/msg/String", HASH) == f"3/chatter/std_msgs::msg::dds_::String_/{HASH}"


def test_qos_strings_leave_defaults_empty_and_read_back() -> None:
    assert RELIABLE.encode() == "::,10:,:,:,,"
    assert SENSOR_DATA.encode() == "2::,5:,:,:,,"
    assert LATCHED.encode() == ":1:,1:,:,:,,"
    for profile in (RELIABLE, SENSOR_DATA, LATCHED):
        assert QosProfile.decode(profile.encode()) == profile
    assert QosProfile.decode("1:2:1,7:,:,:,,") == QosProfile(Reliability.RELIABLE, Durability.VOLATILE, 7)
    with pytest.raises(ValueError, match="6"):
        QosProfile.decode("1:2")


def test_tokens_carry_the_whole_endpoint_and_parse_back() -> None:
    node = GraphNode(0, "aa11", 2, "battery", "/robot")
    assert node.token_key() == "@ros2_lv/0/aa11/2/2/NN/%/%robot/battery"
    endpoint = Endpoint(node, 9, EntityKind.PUBLISHER, "/robot/battery_status", "sensor_msgs/msg/BatteryState",
                        HASH, SENSOR_DATA)
    key = endpoint.token_key()
    assert key == ("@ros2_lv/0/aa11/2/9/MP/%/%robot/battery/%robot%battery_status/"
                   f"sensor_msgs::msg::dds_::BatteryState_/{HASH}/2::,5:,:,:,,")
    assert parse_endpoint_token(key) == endpoint


@pytest.mark.parametrize("key", [
    "@ros2_lv/0/aa11/2/2/NN/%/%/battery",  # a node
    "@ros2_lv/0/aa11/2/9/XX/%/%/n/%t/std_msgs::msg::dds_::String_/h/::,10:,:,:,,",  # unknown kind
    "@ros2_lv/x/aa11/2/9/MS/%/%/n/%t/std_msgs::msg::dds_::String_/h/::,10:,:,:,,",  # domain not a number
    "@ros2_lv/0/aa11/2/9/MS/%/%/n/%t/String/h/::,10:,:,:,,",  # not a DDS type
    "@ros2_lv/0/aa11/2/9/MS/%/%/n/%t/std_msgs::msg::dds_::String_/h/bad",  # QoS
    "elsewhere/0/aa11/2/9/MS/%/%/n/%t/std_msgs::msg::dds_::String_/h/::,10:,:,:,,",
])
def test_malformed_tokens_are_named(key: str) -> None:
    with pytest.raises(ValueError, match="token"):
        parse_endpoint_token(key)


def test_attachment_is_sequence_stamp_and_gid() -> None:
    gid = bytes(range(16))
    data = Attachment(7, 1_700_000_000_123_456_789, gid).encode()
    assert len(data) == 33 and data[:8] == (7).to_bytes(8, "little") and data[16] == 16 and data[17:] == gid
    assert Attachment.decode(data) == Attachment(7, 1_700_000_000_123_456_789, gid)
    with pytest.raises(ValueError, match="33 bytes"):
        Attachment.decode(data[:20])
    with pytest.raises(ValueError, match="16 bytes"):
        Attachment(1, 2, b"short").encode()
