"""What several services' contracts share: flags, QoS and the Nav2 lifecycle requests."""

from __future__ import annotations

from shared.contracts.model import Flag, Request
from shared.endpoints import QoS
from shared.interfaces.lifecycle import CHANGE_STATE, GET_STATE, MANAGE_LIFECYCLE_NODES
from shared.nav2_stand_ins import change_state_service, get_state_service, managers_hosted_by, stand_ins

#: The docking service's phase, in words (``docking/state``).
DOCKING_STATE = "docking/state"
#: Camera images: best effort, only the latest.
IMAGE_QOS = QoS(reliable=False, block=False, depth=1)
CLOCK_QOS = QoS(reliable=True, depth=1)
USE_SIM_TIME = Flag(
    "use_sim_time", "follow the simulator's clock on `clock` (zendock's stacks always set true)", needed=True
)


def lifecycle_requests(service: str) -> tuple[Request, ...]:
    """``<nav2 node>/get_state`` and ``change_state`` for each Nav2 node ``service`` stands in for, and
    ``manage_nodes`` for each lifecycle manager it hosts (:mod:`shared.nav2_stand_ins`)."""
    requests: list[Request] = []
    for name in stand_ins(service):
        requests.append(
            Request(
                get_state_service(name),
                GET_STATE,
                when="for Nav2 scripts (zendock's runtime serves it)",
                about=f"stands in for Nav2's {name}: `active` while the service runs, until a lifecycle change",
            )
        )
        requests.append(
            Request(
                change_state_service(name),
                CHANGE_STATE,
                when="for Nav2's lifecycle managers and `ros2 lifecycle set` (zendock's runtime serves it)",
                about=f"moves {name} between Nav2's lifecycle states; out of `active` it refuses its actions' goals"
                " and cancels the running one",
            )
        )
    for manager in managers_hosted_by(service):
        requests.append(
            Request(
                manager.manage_nodes,
                MANAGE_LIFECYCLE_NODES,
                when="for Nav2 scripts' lifecycleStartup() and lifecycleShutdown() (zendock's runtime serves it)",
                about=f"Nav2's {manager.name}: STARTUP, PAUSE, RESUME, RESET, SHUTDOWN, CONFIGURE or CLEANUP "
                f"of {', '.join(manager.nodes)}, in Nav2's order",
            )
        )
    return tuple(requests)


DOCK_DATABASE = Flag(
    "dock_database",
    "the world file, YAML (docs/worlds.md): its `docks` list, each `{id, pose: [x_m, y_m, yaw_rad], type, "
    "marker_id, marker_size_m}` in the map frame (marker_id: the dock's index when absent; marker_size_m: "
    "0.12 when absent). PyYAML's `yaml.safe_load` reads it",
)
