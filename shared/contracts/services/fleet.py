"""The fleet service's contract."""

from __future__ import annotations

from shared import topics
from shared.contracts.model import Contract, Flag, Request, Topic
from shared.endpoints import BLOCKING
from shared.interfaces.fleet import RELEASE_DOCK, RESERVE_DOCK, FleetDocks, FleetQueue

CONTRACT = Contract(
    service="fleet",
    summary="Shares docks between robots: reservations with leases, a queue, the docks' occupancy.",
    version="1.1",
    publishes=(
        Topic(topics.FLEET_DOCKS, FleetDocks, BLOCKING, rate_hz=1.0, about="every dock's occupancy"),
        Topic(topics.FLEET_QUEUE, FleetQueue, BLOCKING, rate_hz=1.0, about="robots waiting for a dock"),
    ),
    serves=(
        Request(topics.FLEET_RESERVE_DOCK, RESERVE_DOCK, about="a dock for a robot, or a place in the queue"),
        Request(topics.FLEET_RELEASE_DOCK, RELEASE_DOCK, about="give the dock back"),
    ),
    flags=(Flag("world", "the world file whose docks are shared", needed=True),),
    behaviour=("reserves and releases: a robot gets a dock, fleet/docks shows it taken, then free again",),
)
