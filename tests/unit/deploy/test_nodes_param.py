"""``zendock nodes`` and ``zendock param`` without a bus: the graph turned by node, names, output lines."""

from __future__ import annotations

import pytest

from deploy.keys.graph import build_graph
from deploy.nodes import info_lines, list_lines, nodes_of, resolve_node
from deploy.param import parse_value, service_key, table_lines
from shared.interfaces.parameters import ParameterDescriptor
from shared.names import endpoint_token_key, node_token_key

TOKENS = [
    node_token_key("robot1", "battery"),
    endpoint_token_key("pub", "robot1", "battery", "sensor_msgs/msg/BatteryState", "robot1/battery_status"),
    endpoint_token_key("sub", "robot1", "battery", "nav_msgs/msg/Odometry", "robot1/odom"),
    endpoint_token_key(
        "srv", "robot1", "battery", "zendock_msgs/srv/SetBatteryState", "robot1/battery/set_state"
    ),
    endpoint_token_key("sub", "robot1", "docking", "sensor_msgs/msg/BatteryState", "robot1/battery_status"),
    endpoint_token_key(
        "act", "robot1", "docking", "opennav_docking_msgs/action/DockRobot", "robot1/dock_robot"
    ),
]


def test_nodes_are_read_from_the_keys_graph_by_node() -> None:
    nodes = nodes_of(build_graph(TOKENS))
    assert list(nodes) == ["/robot1/battery", "/robot1/docking"]
    assert list_lines(nodes.values()) == ["/robot1/battery", "/robot1/docking (starting)"]
    assert info_lines(nodes["/robot1/battery"]) == [
        "/robot1/battery",
        "  Publishers:",
        "    robot1/battery_status: sensor_msgs/msg/BatteryState",
        "  Subscriptions:",
        "    robot1/odom: nav_msgs/msg/Odometry",
        "  Services:",
        "    robot1/battery/set_state: zendock_msgs/srv/SetBatteryState",
        "  Actions:",
    ]
    assert nodes["/robot1/docking"].to_json()["actions"] == [
        {"key": "robot1/dock_robot", "type": "opennav_docking_msgs/action/DockRobot"}
    ]


@pytest.mark.parametrize(
    ("typed", "namespace", "resolved"),
    [
        ("/robot1/battery", "", "/robot1/battery"),
        ("/robot1/battery", "robot2", "/robot1/battery"),  # absolute, as nodes list prints it
        ("battery", "robot1", "/robot1/battery"),
        ("battery", "", "/battery"),
    ],
)
def test_node_names_as_typed(typed: str, namespace: str, resolved: str) -> None:
    assert resolve_node(typed, namespace) == resolved


def test_parameter_service_keys() -> None:
    assert service_key("/robot1/battery", "set") == "robot1/battery/_param/set"
    assert service_key("/battery", "list") == "battery/_param/list"


def test_values_parse_as_yaml_like_start_up_overrides() -> None:
    assert parse_value("0.5") == 0.5
    assert parse_value("true") is True
    assert parse_value("[0.1, 0, 0]") == [0.1, 0, 0]
    assert parse_value("base_link") == "base_link"
    assert parse_value("{") == "{"


def test_the_list_table() -> None:
    rows = [
        ParameterDescriptor(name="capacity_ah", value_json="2.0"),
        ParameterDescriptor(name="drain_scale", value_json="1.0", settable=True, applies="at once"),
    ]
    assert table_lines(rows) == [
        "NAME         VALUE  SETTABLE",
        "capacity_ah  2.0    no",
        "drain_scale  1.0    yes, at once",
    ]
