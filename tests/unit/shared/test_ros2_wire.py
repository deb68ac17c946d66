"""rmw_zenoh's wire forms: type names, data keys, graph tokens, QoS strings and attachments."""

from __future__ import annotations

import struct

import pytest
import xxhash

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
    entity_gid,
    mangle,
    namespace_error,
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
    assert qualified_name("/robot", "/clock") == "/clock"


@pytest.mark.parametrize("namespace", ["/", "/robot", "/fleet/robot_1", "/_r"])
def test_canonical_namespaces_are_taken(namespace: str) -> None:
    """rcl hands rmw_zenoh namespaces already validated and expanded (``/``, ``/a/b``), and rmw_zenoh mangles
    them as they are (liveliness_utils.cpp, ``mangle_name``: every ``/`` becomes ``%``)."""
    assert namespace_error(namespace) is None
    assert GraphNode(0, "s", 1, "n", namespace).token_key().split("/")[7] == namespace.replace("/", "%")


@pytest.mark.parametrize(
    ("namespace", "why"),
    [
        ("robot", "must start with '/'"),
        ("/robot/", "must not end with '/'"),
        ("//r", "must not contain '//'"),
        ("/r-1", "'r-1' is not a ROS name token"),
        ("/1robot", "'1robot' is not a ROS name token"),
        ("", "must start with '/'"),
    ],
)
def test_other_namespaces_are_refused_with_the_reason(namespace: str, why: str) -> None:
    error = namespace_error(namespace)
    assert error is not None and why in error and "\n" not in error


def test_data_key_is_domain_topic_type_hash() -> None:
    assert (
        data_key(3, "/chatter", "std_msgs/msg/String", HASH)
        == f"3/chatter/std_msgs::msg::dds_::String_/{HASH}"
    )


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
    endpoint = Endpoint(
        node,
        9,
        EntityKind.PUBLISHER,
        "/robot/battery_status",
        "sensor_msgs/msg/BatteryState",
        HASH,
        SENSOR_DATA,
    )
    key = endpoint.token_key()
    assert key == (
        "@ros2_lv/0/aa11/2/9/MP/%/%robot/battery/%robot%battery_status/"
        f"sensor_msgs::msg::dds_::BatteryState_/{HASH}/2::,5:,:,:,,"
    )
    assert parse_endpoint_token(key) == endpoint


@pytest.mark.parametrize(
    "key",
    [
        "@ros2_lv/0/aa11/2/2/NN/%/%/battery",  # a node
        "@ros2_lv/0/aa11/2/9/XX/%/%/n/%t/std_msgs::msg::dds_::String_/h/::,10:,:,:,,",  # unknown kind
        "@ros2_lv/x/aa11/2/9/MS/%/%/n/%t/std_msgs::msg::dds_::String_/h/::,10:,:,:,,",  # domain not a number
        "@ros2_lv/0/aa11/2/9/MS/%/%/n/%t/String/h/::,10:,:,:,,",  # not a DDS type
        "@ros2_lv/0/aa11/2/9/MS/%/%/n/%t/std_msgs::msg::dds_::String_/h/bad",  # QoS
        "elsewhere/0/aa11/2/9/MS/%/%/n/%t/std_msgs::msg::dds_::String_/h/::,10:,:,:,,",
    ],
)
def test_malformed_tokens_are_named(key: str) -> None:
    with pytest.raises(ValueError, match="token"):
        parse_endpoint_token(key)


def test_a_gid_is_the_xxh3_128_hash_of_the_token_key() -> None:
    """rmw_zenoh (liveliness_utils.cpp, ``Entity::Entity``) hashes the entity's liveliness key with
    ``simplified_XXH3_128bits`` and memcpys ``low64`` then ``high64`` (host order, little endian) into the
    16-byte gid it sends in every attachment (rmw_publisher_data.cpp, ``entity_->copy_gid()``)."""
    assert (
        xxhash.xxh3_128_intdigest(b"") == 0x99AA06D3014798D86001C324468D497F
    )  # XXH3-128 seed 0: the standard
    endpoint = Endpoint(
        GraphNode(0, "aa11", 2, "battery"),
        9,
        EntityKind.PUBLISHER,
        "/battery_status",
        "sensor_msgs/msg/BatteryState",
        HASH,
    )
    key = endpoint.token_key()
    value = xxhash.xxh3_128_intdigest(key.encode())
    low64, high64 = value & (2**64 - 1), value >> 64
    assert entity_gid(key) == struct.pack("<QQ", low64, high64)
    assert entity_gid(key) != entity_gid(key.replace("/9/", "/10/"))


def test_attachment_is_sequence_stamp_and_gid() -> None:
    gid = bytes(range(16))
    data = Attachment(7, 1_700_000_000_123_456_789, gid).encode()
    assert len(data) == 33 and data[:8] == (7).to_bytes(8, "little") and data[16] == 16 and data[17:] == gid
    assert Attachment.decode(data) == Attachment(7, 1_700_000_000_123_456_789, gid)
    with pytest.raises(ValueError, match="33 bytes"):
        Attachment.decode(data[:20])
    with pytest.raises(ValueError, match="16 bytes"):
        Attachment(1, 2, b"short").encode()
