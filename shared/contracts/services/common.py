"""What several services' contracts share: flags, QoS and the Nav2 lifecycle requests."""

from __future__ import annotations

from shared.contracts.model import Flag, Request
from shared.endpoints import QoS
from shared.interfaces.lifecycle import GET_STATE
from shared.nav2_stand_ins import get_state_service, stand_ins

#: The docking service's phase, in words (``docking/state``).
DOCKING_STATE = "docking/state"
#: Camera images: best effort, only the latest.
IMAGE_QOS = QoS(reliable=False, block=False, depth=1)
CLOCK_QOS = QoS(reliable=True, depth=1)
USE_SIM_TIME = Flag(
    "use_sim_time", "follow the simulator's clock on `clock` (zendock's stacks always set true)", needed=True
)


def lifecycle_requests(service: str) -> tuple[Request, ...]:
    """``<nav2 node>/get_state`` for each Nav2 node ``service`` stands in for (:mod:`shared.nav2_stand_ins`)."""
    return tuple(
        Request(
            get_state_service(name),
            GET_STATE,
            when="for Nav2 scripts (zendock's runtime serves it)",
            about=f"stands in for Nav2's {name}: `active` while the service runs",
        )
        for name in stand_ins(service)
    )


DOCK_DATABASE = Flag("dock_database", "the world file: its docks (pose, marker id, size) and staging offsets")
