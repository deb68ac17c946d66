"""Which zendock service stands in for which of Nav2's lifecycle nodes, for scripts that ask.

A Nav2 script waits for ``amcl`` and ``bt_navigator`` to be ``active`` (``<node>/get_state``) and may ask
the others; zendock runs no particle filter and no behaviour tree, so the service that does each job
answers for that node's name: the pose service for ``amcl`` (map -> base_link; it publishes
``amcl_pose``), the planner for Nav2's navigation servers, the docking service for ``docking_server``.
A zendock service serves ``<name>/get_state`` for each node it stands in for, always ``active``: it has
no lifecycle, and one that serves is running (:mod:`shared.lifecycle_states`). The ROS 2 faces carry
these services as they carry any. Pure: the contracts and the faces read the table without the bus.
"""

from __future__ import annotations

#: Nav2 lifecycle node -> the zendock service that answers for it.
NAV2_STAND_INS: dict[str, str] = {
    "amcl": "pose",
    "map_server": "planner",
    "planner_server": "planner",
    "controller_server": "planner",
    "smoother_server": "planner",
    "behavior_server": "planner",
    "bt_navigator": "planner",
    "waypoint_follower": "planner",
    "docking_server": "docking",
}


def stand_ins(service: str) -> tuple[str, ...]:
    """The Nav2 nodes ``service`` answers for (none for most services)."""
    return tuple(node for node, owner in NAV2_STAND_INS.items() if owner == service)


def get_state_service(nav2_node: str) -> str:
    """``amcl`` -> ``amcl/get_state`` (relative to the robot's namespace, as Nav2's)."""
    return f"{nav2_node}/get_state"
