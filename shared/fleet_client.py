"""A client of the fleet service's dock reservations, for a robot's services (and tools, tests).

    fleet = FleetClient(node)                        # the fleet one namespace above the node's
    fleet.reserve(battery=0.2, on_answer=handle)     # handle(FleetAnswer | None, ServiceError | None)
    fleet.reserve(0.2, "", {"west": 3.1, "east": 9.0}, on_answer=handle)
    fleet.release(on_done=handle_release)            # handle_release(dock_id | None, ServiceError | None)

Nothing blocks: each answer comes later on the node's executor, so a service calls these from its own
callbacks. A robot is named by its node's namespace (``r1``); the fleet service serves the robots of a
room from the namespace above theirs (``fleet/reserve_dock`` for ``r1``, ``site/fleet/...`` for
``site/r1``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from shared import topics
from shared.fleet_answer import FleetAnswer
from shared.interfaces.fleet import (
    RELEASE_DOCK,
    RESERVE_DOCK,
    ReleaseDockRequest,
    ReleaseDockResponse,
    ReserveDockRequest,
    ReserveDockResponse,
)
from shared.names import topic_key
from shared.node import Node, ServiceError

#: How long a request waits for the fleet's answer.
ANSWER_TIMEOUT_S = 1.0


class FleetClient:
    """Reserve and release docks for the robot of ``node`` (see the module docstring)."""

    def __init__(self, node: Node) -> None:
        self._node = node
        self.robot = node.namespace
        fleet_namespace = node.namespace.rpartition("/")[0]
        self.reserve_key = topic_key(fleet_namespace, topics.FLEET_RESERVE_DOCK)
        self.release_key = topic_key(fleet_namespace, topics.FLEET_RELEASE_DOCK)

    def reserve(
        self,
        battery: float,
        dock_id: str = "",
        path_lengths: Mapping[str, float] | None = None,
        *,
        on_answer: Callable[[FleetAnswer | None, ServiceError | None], Any],
    ) -> None:
        """Ask for ``dock_id`` ("" : the nearest free one by ``path_lengths``, dock id -> metres; a dock left
        out is out of reach, None: all reachable) at charge ``battery`` (0..1); asking again renews."""
        lengths = dict(path_lengths or {})
        request = ReserveDockRequest(
            robot=self.robot,
            battery=float(battery),
            dock_id=dock_id,
            dock_ids=list(lengths),
            path_lengths=np.asarray(list(lengths.values()), dtype=float),
        )

        def answered(response: ReserveDockResponse | None, error: ServiceError | None) -> None:
            on_answer(FleetAnswer.from_response(response) if response is not None else None, error)

        self._node.call_async(
            RESERVE_DOCK, self.reserve_key, request, answered, timeout_s=ANSWER_TIMEOUT_S, absolute=True
        )

    def release(self, *, on_done: Callable[[str | None, ServiceError | None], Any]) -> None:
        """Give back the robot's dock; ``on_done`` gets the dock it held ("" if none)."""

        def answered(response: ReleaseDockResponse | None, error: ServiceError | None) -> None:
            on_done(response.dock_id if response is not None else None, error)

        self._node.call_async(
            RELEASE_DOCK,
            self.release_key,
            ReleaseDockRequest(robot=self.robot),
            answered,
            timeout_s=ANSWER_TIMEOUT_S,
            absolute=True,
        )
