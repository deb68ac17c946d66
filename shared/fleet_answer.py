"""The fleet's answer to a dock reservation, as a robot's docking logic reads it (pure: no bus).

:class:`~shared.fleet_client.FleetClient` asks the fleet service and hands the answer on as a
:class:`FleetAnswer`; the docking executive and its dock claim decide on it without loading Zenoh.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from shared.geometry import Pose2D

if TYPE_CHECKING:
    from shared.interfaces.fleet import ReserveDockResponse


@dataclass(frozen=True, slots=True)
class FleetAnswer:
    """The fleet's answer to a reservation: a dock (``granted``, ``dock_id``), or a place in the queue
    (1 = next) with why and where to wait (``holding_pose``, None: where the robot stands); and whether
    a robot whose battery is critical needs this robot's dock (``asked_to_leave``)."""

    granted: bool
    dock_id: str = ""
    queue_position: int = 0
    reason: str = ""
    asked_to_leave: bool = False
    holding_pose: Pose2D | None = None

    @property
    def refused(self) -> bool:
        """Neither a dock nor a place in the queue: the request itself was wrong (``reason`` says why)."""
        return not self.granted and self.queue_position == 0

    @classmethod
    def from_response(cls, response: ReserveDockResponse) -> FleetAnswer:
        pose = np.asarray(response.holding_pose, dtype=float)
        holding = Pose2D.from_seq(pose) if pose.size == 3 and np.all(np.isfinite(pose)) else None
        return cls(
            bool(response.granted),
            response.dock_id,
            int(response.queue_position),
            response.reason,
            bool(response.asked_to_leave),
            holding,
        )
