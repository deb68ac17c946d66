"""Which zendock service stands in for which of Nav2's lifecycle nodes, for scripts that ask.

A Nav2 script waits for ``amcl`` and ``bt_navigator`` to be ``active`` (``<node>/get_state``) and may ask
the others; zendock runs no particle filter and no behaviour tree, so the service that does each job
answers for that node's name: the pose service for ``amcl`` (map -> base_link; it publishes
``amcl_pose``), the planner for Nav2's navigation servers, the docking service for ``docking_server``.
A zendock service serves ``<name>/get_state`` and ``<name>/change_state`` for each node it stands in for
(:mod:`shared.lifecycle_states`): it starts ``active``, and a node taken out of ``active`` (by its
lifecycle manager, say) refuses the actions it owns (:data:`NAV2_WORK`) until it is active again. Nav2's
two lifecycle managers are served by the service named in :data:`NAV2_LIFECYCLE_MANAGERS`. The ROS 2
faces carry these services as they carry any. Pure: the contracts and the faces read the tables without
the bus.
"""

from __future__ import annotations

import msgspec

from shared import topics

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


def change_state_service(nav2_node: str) -> str:
    """``amcl`` -> ``amcl/change_state``."""
    return f"{nav2_node}/change_state"


#: Each of zendock's Nav2 actions -> the Nav2 node whose work it is (a node not active refuses it).
NAV2_WORK: dict[str, str] = {
    topics.NAVIGATE_TO_POSE: "bt_navigator",
    topics.NAVIGATE_THROUGH_POSES: "bt_navigator",
    topics.COMPUTE_PATH_TO_POSE: "planner_server",
    topics.COMPUTE_PATH_THROUGH_POSES: "planner_server",
    topics.FOLLOW_PATH: "controller_server",
    topics.SMOOTH_PATH: "smoother_server",
    topics.SPIN: "behavior_server",
    topics.BACKUP: "behavior_server",
    topics.DRIVE_ON_HEADING: "behavior_server",
    topics.WAIT: "behavior_server",
    topics.ASSISTED_TELEOP: "behavior_server",
    topics.FOLLOW_WAYPOINTS: "waypoint_follower",
    topics.FOLLOW_GPS_WAYPOINTS: "waypoint_follower",
    topics.DOCK_ROBOT: "docking_server",
    topics.UNDOCK_ROBOT: "docking_server",
}


class LifecycleManager(msgspec.Struct, frozen=True):
    """One of Nav2's lifecycle managers: the zendock service that serves its ``manage_nodes``, and the
    nodes it manages in Nav2's bring-up order (those zendock stands in for)."""

    name: str
    host: str
    nodes: tuple[str, ...]

    @property
    def manage_nodes(self) -> str:
        return f"{self.name}/manage_nodes"


#: Nav2's two managers, as its bring-up launches them (nodes zendock does not stand in for left out).
NAV2_LIFECYCLE_MANAGERS: tuple[LifecycleManager, ...] = (
    LifecycleManager(
        "lifecycle_manager_navigation",
        "planner",
        (
            "controller_server",
            "smoother_server",
            "planner_server",
            "behavior_server",
            "bt_navigator",
            "waypoint_follower",
            "docking_server",
        ),
    ),
    LifecycleManager("lifecycle_manager_localization", "pose", ("map_server", "amcl")),
)


def managers_hosted_by(service: str) -> tuple[LifecycleManager, ...]:
    """The lifecycle managers ``service`` serves ``manage_nodes`` for."""
    return tuple(m for m in NAV2_LIFECYCLE_MANAGERS if m.host == service)
