"""What the fuzzer aims at: graph tokens and known names, merged and typed; loopback only."""

from __future__ import annotations

import pytest

from deploy.fuzz.campaign import FuzzOptions, check_loopback
from deploy.fuzz.targets import REQUEST, TOPIC, graph_targets, known_targets, merge_targets
from deploy.keys.types import known_types
from shared.names import endpoint_token_key, node_token_key, parse_token_key


def _entries(*tokens: str):  # type: ignore[no-untyped-def]
    return [parse_token_key(t) for t in tokens]


def test_graph_tokens_become_typed_targets() -> None:
    entries = _entries(
        node_token_key("r1", "simulator"),
        endpoint_token_key("sub", "r1", "simulator", "geometry_msgs/msg/Twist", "r1/cmd_vel"),
        endpoint_token_key("pub", "r1", "simulator", "nav_msgs/msg/Odometry", "r1/odom"),
        endpoint_token_key("srv", "r1", "simulator", "zendock_msgs/srv/Teleport", "r1/simulator/teleport"),
        endpoint_token_key("act", "r1", "docking", "opennav_docking_msgs/action/DockRobot", "r1/dock_robot"),
        endpoint_token_key("sub", "other", "pose", "tf2_msgs/msg/TFMessage", "other/tf"),
    )
    targets = {t.key: t for t in graph_targets(entries, "r1")}
    assert targets["r1/cmd_vel"].kind == TOPIC and targets["r1/cmd_vel"].announced
    assert targets["r1/odom"].type_name == "nav_msgs/msg/Odometry" and not targets["r1/odom"].announced
    assert targets["r1/simulator/teleport"].type_name == "zendock_msgs/srv/Teleport_Request"
    assert (
        targets["r1/dock_robot/_action/send_goal"].type_name
        == "opennav_docking_msgs/action/DockRobot_SendGoal_Request"
    )
    assert targets["r1/dock_robot/_action/get_result"].empty_request == b""
    assert targets["r1/dock_robot/_action/cancel_goal"].type_name == "action_msgs/srv/CancelGoal_Request"
    assert "other/tf" not in targets


def test_known_names_fill_in_and_the_graph_gives_their_types() -> None:
    entries = _entries(
        endpoint_token_key("sub", "r1", "simulator", "geometry_msgs/msg/Twist", "r1/cmd_vel"),
        endpoint_token_key("sub", "r1", "viz", "geometry_msgs/msg/Twist", "r1/**"),
    )
    targets, skipped = merge_targets([*graph_targets(entries, "r1"), *known_targets("r1")], known_types())
    by_key = {(t.kind, t.key): t for t in targets}
    assert by_key[(TOPIC, "r1/cmd_vel")].type_name == "geometry_msgs/msg/Twist"
    assert by_key[(TOPIC, "r1/scan")].type_name is None and not by_key[(TOPIC, "r1/scan")].announced
    assert (REQUEST, "r1/navigate_to_pose/_action/get_result") in by_key
    assert skipped == ["r1/**"]
    assert len(by_key) == len(targets)


def test_a_type_nobody_registered_is_treated_as_unknown() -> None:
    entries = _entries(endpoint_token_key("sub", "", "x", "foreign_msgs/msg/Thing", "thing"))
    (target,), _ = merge_targets(graph_targets(entries, ""), known_types())
    assert target.key == "thing" and target.type_name is None


@pytest.mark.parametrize(
    "endpoint",
    [
        "tcp/127.0.0.1:7447",
        "tcp/localhost:1",
        "udp/[::1]:7447",
        "tls/127.0.0.2:7448",
        "unixsock-stream//tmp/z.sock",
    ],
)
def test_loopback_endpoints_are_accepted(endpoint: str) -> None:
    check_loopback([endpoint])


@pytest.mark.parametrize(
    "endpoint",
    ["tcp/192.168.1.10:7447", "tcp/example.com:7447", "tcp/[2001:db8::1]:7447", "tcp/0.0.0.0:7447"],
)
def test_other_endpoints_are_refused(endpoint: str) -> None:
    with pytest.raises(ValueError, match="not a loopback endpoint"):
        FuzzOptions(connect=(endpoint,))
    with pytest.raises(ValueError, match="not a loopback endpoint"):
        check_loopback(["tcp/127.0.0.1:7447", endpoint])
