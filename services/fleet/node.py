"""The fleet service's wiring: dock reservations on the bus (see :mod:`services.fleet.dock_book`).

``fleet/reserve_dock`` and ``fleet/release_dock`` answer the robots' docking services;
``fleet/docks`` and ``fleet/queue`` say, each second and after every change, who holds which dock and
who waits. A robot is alive while its docking node's liveliness token is (``@zendock/node/<ns>/docking``):
its claim's lease runs from the last moment it was seen alive, so a killed robot's dock is free again
``lease_s`` after its token went, and a restart within that time finds the dock still its own.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
import zenoh
from msgspec import Meta

from services.fleet.dock_book import DockBook
from shared import topics
from shared.config_errors import ConfigError
from shared.interfaces.fleet import (
    RELEASE_DOCK,
    RESERVE_DOCK,
    DockOccupancy,
    FleetDocks,
    FleetQueue,
    QueuedRobot,
    ReleaseDockRequest,
    ReleaseDockResponse,
    ReserveDockRequest,
    ReserveDockResponse,
)
from shared.messages import Header
from shared.names import GRAPH_PREFIX, decode_chunk, normalise_namespace
from shared.node import BLOCKING, Node
from shared.parameters import ServiceParams
from shared.runtime import ServiceSpec
from shared.structs import blaming
from shared.world import load_world

#: The robots' docking nodes' liveliness tokens: ``@zendock/node/<namespace>/docking``.
DOCKING_TOKENS = f"{GRAPH_PREFIX}/node/*/docking"


class Params(ServiceParams):
    """Parameters of ``python -m services.fleet`` (``-p name=value`` or a YAML file)."""

    world: Annotated[str, Meta(description="world file whose docks the fleet shares out")]
    lease_s: Annotated[
        float, Meta(gt=0.0, description="a robot not seen alive for this long loses its dock")
    ] = 10.0
    critical_battery: Annotated[
        float,
        Meta(
            ge=0.0,
            le=1.0,
            description="at or below this a waiting robot may ask a charged one to leave its dock",
        ),
    ] = 0.10
    charged_enough: Annotated[
        float, Meta(gt=0.0, le=1.0, description="a robot charged to this may be asked to leave")
    ] = 0.60
    publish_period_s: Annotated[
        float, Meta(gt=0.0, description="fleet/docks and fleet/queue at least this often")
    ] = 1.0

    def __post_init__(self) -> None:
        with blaming("world"):
            docks = load_world(self.world).docks
        if not docks:
            raise ValueError(f"world: {self.world} has no docks to share")
        if self.critical_battery >= self.charged_enough:
            raise ValueError("critical_battery must be below charged_enough")


class FleetService:
    """The dock book on a node; see the module docstring."""

    def __init__(self, node: Node, params: Params) -> None:
        self._node = node
        self._log = node.log
        world = load_world(params.world)
        self._holding_poses = [tuple(map(float, p)) for p in world.holding]
        try:
            self.book = DockBook(
                tuple(d.id for d in world.docks),
                lease_s=params.lease_s,
                critical_battery=params.critical_battery,
                charged_enough=params.charged_enough,
                holding_spots=len(self._holding_poses),
            )
        except ValueError as exc:
            raise ConfigError(f"{params.world}: {exc}") from None
        #: Robots whose docking node is alive now (their namespaces), from liveliness (Zenoh's thread
        #: adds and removes; the executor reads a copy).
        self._alive: set[str] = set()
        self._docks_pub = node.create_publisher(FleetDocks, topics.FLEET_DOCKS, BLOCKING)
        self._queue_pub = node.create_publisher(FleetQueue, topics.FLEET_QUEUE, BLOCKING)
        node.create_service(RESERVE_DOCK, topics.FLEET_RESERVE_DOCK, self._on_reserve)
        node.create_service(RELEASE_DOCK, topics.FLEET_RELEASE_DOCK, self._on_release)
        self._watch = node.session.liveliness().declare_subscriber(
            DOCKING_TOKENS, self._on_token, history=True
        )
        self._timer = node.create_timer(params.publish_period_s, self._tick, wall=True)
        self._log.info(
            "sharing %d dock(s) of %s: %s (lease %g s)",
            len(world.docks),
            world.name,
            ", ".join(self.book.dock_ids),
            params.lease_s,
        )

    def _on_token(self, sample: zenoh.Sample) -> None:
        """Zenoh's thread: a docking node appeared or went. Only the set changes here."""
        chunks = str(sample.key_expr).split("/")
        if len(chunks) != 4:
            return
        robot = decode_chunk(chunks[2])
        if sample.kind == zenoh.SampleKind.PUT:
            self._alive.add(robot)
        else:
            self._alive.discard(robot)

    def _on_reserve(self, request: ReserveDockRequest) -> ReserveDockResponse:
        robot = normalise_namespace(request.robot)
        if len(request.dock_ids) != len(request.path_lengths):
            return ReserveDockResponse(
                reason=f"{len(request.dock_ids)} dock ids but {len(request.path_lengths)} path lengths"
            )
        if not 0.0 <= request.battery <= 1.0:
            return ReserveDockResponse(reason=f"battery {request.battery} is not a fraction in [0, 1]")
        lengths = dict(
            zip(request.dock_ids, np.asarray(request.path_lengths, dtype=float).tolist(), strict=True)
        )
        before = self.book.holding(robot)
        try:
            decision = self.book.request(
                robot,
                request.battery,
                self._node.now(),
                wanted=request.dock_id or None,
                path_lengths_m=lengths or None,
            )
        except ValueError as exc:
            return ReserveDockResponse(reason=str(exc))
        if decision.granted and before is None:
            self._log.info(
                "%s reserved dock %s at %.0f %% charge",
                robot or "(root)",
                decision.dock_id,
                100.0 * request.battery,
            )
            self._publish()
        elif not decision.granted and decision.queue_position:
            self._publish()
        spot = decision.holding_spot
        return ReserveDockResponse(
            granted=decision.granted,
            dock_id=decision.dock_id or "",
            queue_position=decision.queue_position,
            reason=decision.reason,
            asked_to_leave=robot in self.book.leave_requests,
            holding_pose=np.asarray(self._holding_poses[spot] if spot is not None else (), dtype=float),
        )

    def _on_release(self, request: ReleaseDockRequest) -> ReleaseDockResponse:
        robot = normalise_namespace(request.robot)
        dock = self.book.release(robot)
        if dock is not None:
            self._log.info("%s released dock %s", robot or "(root)", dock)
        self._publish()
        return ReleaseDockResponse(dock_id=dock or "")

    def _tick(self) -> None:
        now = self._node.now()
        for robot in list(self._alive):
            self.book.heard_from(robot, now)
        for claim in self.book.expire(now):
            self._log.warning(
                "%s not seen alive for %g s: its dock %s is free again",
                claim.robot or "(root)",
                self.book.lease_s,
                claim.dock_id,
            )
        self._publish()

    def _publish(self) -> None:
        header = Header.at(self._node.now(), "")
        claims = self.book.claims
        self._docks_pub.publish(
            FleetDocks(
                header,
                [
                    DockOccupancy(d, claims[d].robot, claims[d].since_s, claims[d].heard_s)
                    if d in claims
                    else DockOccupancy(d)
                    for d in self.book.dock_ids
                ],
            )
        )
        self._queue_pub.publish(
            FleetQueue(header, [QueuedRobot(w.robot, w.battery, w.since_s) for w in self.book.queue_order()])
        )

    def close(self) -> None:
        self._timer.cancel()
        self._watch.undeclare()


SERVICE = ServiceSpec(
    "fleet",
    Params,
    FleetService,
    description="Shares a room's docks among robots: reservations, leases and a queue.",
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
