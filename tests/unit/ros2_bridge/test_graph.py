"""ROS 2 sees a zendock service's node and endpoints while, and only while, the service is up."""

from __future__ import annotations

from services.ros2_bridge.graph import GraphMirror
from shared.ros2.wire import RELIABLE, Endpoint, EntityKind, GraphNode


class _Token:
    def __init__(self, live: set[str], key: str) -> None:
        self.live, self.key = live, key
        live.add(key)

    def undeclare(self) -> None:
        self.live.remove(self.key)


def test_a_service_is_shown_while_it_is_up_and_the_bridge_always() -> None:
    live: set[str] = set()
    nodes = {name: GraphNode(0, "s", i, name) for i, name in enumerate(("ros2_bridge", "battery"))}
    graph = GraphMirror(nodes, lambda key: _Token(live, key), always="ros2_bridge")
    status = Endpoint(
        nodes["battery"],
        7,
        EntityKind.PUBLISHER,
        "/battery_status",
        "sensor_msgs/msg/BatteryState",
        "RIHS01_x",
        RELIABLE,
    )
    graph.add(status)
    assert live == {nodes["ros2_bridge"].token_key()}  # the battery is not up yet
    assert graph.present("battery") and not graph.present("battery")
    assert live == {nodes["ros2_bridge"].token_key(), nodes["battery"].token_key(), status.token_key()}
    assert graph.absent("battery") and not graph.absent("ros2_bridge") and not graph.present("planner")
    assert live == {nodes["ros2_bridge"].token_key()}
    graph.close()
    assert live == set()
