"""The graph of keys built from liveliness tokens and the router's admin space."""

from __future__ import annotations

from deploy.keys.graph import Endpoint, admin_key, build_graph, node_display_name
from shared.names import endpoint_token_key, node_token_key

TWIST = "geometry_msgs/msg/Twist"


def _tokens() -> list[str]:
    return [
        node_token_key("robot1", "teleop"),
        endpoint_token_key("pub", "robot1", "teleop", TWIST, "robot1/cmd_vel"),
        endpoint_token_key("sub", "robot1", "simulator", TWIST, "robot1/cmd_vel"),
        endpoint_token_key("sub", "robot1", "recorder", TWIST, "robot1/cmd_vel"),
        endpoint_token_key(
            "srv", "robot1", "simulator", "zendock_msgs/srv/Teleport", "robot1/simulator/teleport"
        ),
        endpoint_token_key("act", "robot1", "docking", "zendock_msgs/action/DockRobot", "robot1/dock_robot"),
        endpoint_token_key("pub", "", "clock_source", "rosgraph_msgs/msg/Clock", "clock"),
        "@zendock/unknown/x/y",  # foreign or malformed tokens are ignored
        "other/prefix/thing",
    ]


def test_endpoints_grouped_by_key_with_types_and_nodes() -> None:
    graph = build_graph(_tokens())
    cmd_vel = graph.keys["robot1/cmd_vel"]
    assert cmd_vel.types == [TWIST] and cmd_vel.topic_types == [TWIST]
    assert cmd_vel.of_kind("pub") == [Endpoint("pub", "/robot1/teleop", TWIST)]
    assert [e.node for e in cmd_vel.of_kind("sub")] == ["/robot1/recorder", "/robot1/simulator"]
    assert graph.keys["robot1/simulator/teleport"].is_service
    assert graph.keys["robot1/dock_robot"].is_action
    assert graph.keys["robot1/dock_robot"].topic_types == []  # pub cannot borrow an action's type
    assert graph.nodes == ["/robot1/teleop"]
    assert set(graph.keys) == {"robot1/cmd_vel", "robot1/simulator/teleport", "robot1/dock_robot", "clock"}


def test_duplicate_tokens_count_once() -> None:
    token = endpoint_token_key("pub", "robot1", "teleop", TWIST, "robot1/cmd_vel")
    assert len(build_graph([token, token]).keys["robot1/cmd_vel"].endpoints) == 1


def test_namespace_filter_and_wildcard_matching() -> None:
    graph = build_graph(_tokens())
    assert [e.key for e in graph.in_namespace("robot1")] == [
        "robot1/cmd_vel",
        "robot1/dock_robot",
        "robot1/simulator/teleport",
    ]
    assert [e.key for e in graph.in_namespace("")][0] == "clock"
    assert [e.key for e in graph.in_namespace("robot")] == []  # a prefix of a chunk is not a namespace
    assert [e.key for e in graph.matching("robot1/*")] == ["robot1/cmd_vel", "robot1/dock_robot"]
    assert [e.key for e in graph.matching("robot1/cmd_vel")] == ["robot1/cmd_vel"]


def test_admin_space_adds_untokened_keys_and_kinds() -> None:
    admin = [
        ("pub", "robot1/cmd_vel"),  # already known from a pub token: nothing new
        ("sub", "robot1/cmd_vel"),
        ("pub", "robot1/raw_camera"),
        ("srv", "@/1234/router"),  # the admin space's own queryable
    ]
    graph = build_graph(_tokens(), admin)
    assert graph.keys["robot1/cmd_vel"].anonymous == set()
    raw = graph.keys["robot1/raw_camera"]
    assert not raw.has_token and raw.anonymous == {"pub"} and raw.types == []
    assert not any(k.startswith("@") for k in graph.keys)


def test_admin_sample_keys_parse_to_bus_keys() -> None:
    assert admin_key("@/abcd/router/publisher/robot1/odom", "publisher") == "robot1/odom"
    assert admin_key("@/abcd/router/subscriber/robot1/**", "subscriber") == "robot1/**"
    assert admin_key("@/abcd/router/linkstate/routers", "publisher") is None
    assert admin_key("@/abcd/router", "publisher") is None


def test_node_names_read_like_ros() -> None:
    assert node_display_name("robot1", "simulator") == "/robot1/simulator"
    assert node_display_name("", "simulator") == "/simulator"
