"""Every Nav2 node a script waits for has a zendock service answering for it, and only services that run."""

from __future__ import annotations

from shared.contracts.services import CONTRACTS
from shared.nav2_stand_ins import NAV2_STAND_INS, get_state_service, stand_ins
from shared.ros2.bridge_routes import SERVICES

#: The lifecycle nodes of Nav2's navigation and localisation (and docking) that scripts ask about.
NAV2_LIFECYCLE_NODES = {
    "amcl",
    "bt_navigator",
    "map_server",
    "planner_server",
    "controller_server",
    "smoother_server",
    "behavior_server",
    "waypoint_follower",
    "docking_server",
}


def test_each_nav2_node_has_a_zendock_service_with_a_contract_naming_its_get_state() -> None:
    assert set(NAV2_STAND_INS) == NAV2_LIFECYCLE_NODES
    contracts = CONTRACTS
    for nav2_node, owner in NAV2_STAND_INS.items():
        assert owner in contracts, owner
        assert get_state_service(nav2_node) in {r.name for r in contracts[owner].serves}, nav2_node
    assert stand_ins("pose") == ("amcl",) and stand_ins("battery") == ()


def test_both_ros2_faces_carry_every_get_state_and_the_costmap_services() -> None:
    carried = {s.name: s.ros_type for s in SERVICES}
    assert {get_state_service(n) for n in NAV2_LIFECYCLE_NODES} <= set(carried)
    assert {carried[get_state_service(n)] for n in NAV2_LIFECYCLE_NODES} == {"lifecycle_msgs/srv/GetState"}
    assert (
        carried["global_costmap/get_costmap"]
        == carried["local_costmap/get_costmap"]
        == ("nav2_msgs/srv/GetCostmap")
    )
    assert carried["global_costmap/clear_entirely_global_costmap"] == "nav2_msgs/srv/ClearEntireCostmap"
    assert carried["map_server/load_map"] == "nav2_msgs/srv/LoadMap"
    assert all(s.unanswered is not None for s in SERVICES)  # a script waits for its reply, unbounded
