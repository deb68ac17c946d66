"""The fleet service's messages and requests: dock reservations for robots sharing a room.

A robot's docking service asks ``fleet/reserve_dock`` before it drives to a dock (and again each second
while it waits or holds one: asking renews), and calls ``fleet/release_dock`` when it undocks. The
fleet publishes ``fleet/docks`` (who holds which dock) and ``fleet/queue`` (who waits, in service order).
"""

from __future__ import annotations

from dataclasses import field

import numpy as np

from shared.interface_types import ServiceType
from shared.messages import Header
from shared.schema import Float64Array, Message, UInt32, message


@message("zendock_msgs/srv/ReserveDock_Request")
class ReserveDockRequest(Message):
    """``robot`` (its namespace) at ``battery`` (0..1) asks for ``dock_id`` ("" for the nearest free one);
    ``dock_ids`` with ``path_lengths`` (same order, metres) say how far each dock it can reach is (a dock
    left out is out of its reach; both empty: every dock counts as reachable)."""

    robot: str = ""
    battery: float = 0.0
    dock_id: str = ""
    dock_ids: list[str] = field(default_factory=list)
    path_lengths: Float64Array = field(default_factory=lambda: np.zeros(0))


@message("zendock_msgs/srv/ReserveDock_Response")
class ReserveDockResponse(Message):
    """``granted`` with the ``dock_id`` now the robot's; else its ``queue_position`` (1 = next) and why."""

    granted: bool = False
    dock_id: str = ""
    queue_position: UInt32 = 0
    reason: str = ""
    #: Set when a robot whose battery is critical waits for this robot's dock: leave it when charged enough.
    asked_to_leave: bool = False
    #: A queued robot's holding pose ``[x, y, yaw]`` in the map frame, its own while it waits (empty: none
    #: free, wait where it stands).
    holding_pose: Float64Array = field(default_factory=lambda: np.zeros(0))


@message("zendock_msgs/srv/ReleaseDock_Request")
class ReleaseDockRequest(Message):
    robot: str = ""


@message("zendock_msgs/srv/ReleaseDock_Response")
class ReleaseDockResponse(Message):
    """The dock the robot held ("" if none)."""

    dock_id: str = ""


@message("zendock_msgs/msg/DockOccupancy")
class DockOccupancy(Message):
    """One dock: the robot holding it ("" when free), since when, and when it was last heard from."""

    dock_id: str = ""
    robot: str = ""
    since: float = 0.0
    heard: float = 0.0


@message("zendock_msgs/msg/FleetDocks")
class FleetDocks(Message):
    header: Header = field(default_factory=Header)
    docks: list[DockOccupancy] = field(default_factory=list)


@message("zendock_msgs/msg/QueuedRobot")
class QueuedRobot(Message):
    robot: str = ""
    battery: float = 0.0
    since: float = 0.0


@message("zendock_msgs/msg/FleetQueue")
class FleetQueue(Message):
    """Robots waiting for a dock, in the order they will be served (lowest battery first)."""

    header: Header = field(default_factory=Header)
    robots: list[QueuedRobot] = field(default_factory=list)


RESERVE_DOCK = ServiceType("zendock_msgs/srv/ReserveDock", ReserveDockRequest, ReserveDockResponse)
RELEASE_DOCK = ServiceType("zendock_msgs/srv/ReleaseDock", ReleaseDockRequest, ReleaseDockResponse)
