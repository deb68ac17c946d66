"""One driver at a time: the docking service's cmd_vel and the planner's goals never overlap.

Before the service publishes a velocity, the planner must hold no goal: a running goal is cancelled
(the request is repeated every ``cancel_retry_s`` in case it reached the server before the goal did)
and nothing is published until it has ended. Before a goal is sent, the service stops
publishing, after one zero command if the last command it published moved the robot. The node asks
the arbiter for :class:`DriveOrders` and carries them out in order: cancel, publish, send.
"""

from __future__ import annotations

from dataclasses import dataclass

from services.docking.task_io import Navigate, Velocity
from shared.geometry import Pose2D

ZERO = Velocity(0.0, 0.0)


@dataclass(frozen=True, slots=True)
class DriveOrders:
    """What the node does this tick: cancel the planner's goal, publish a command, send a goal."""

    cancel_nav: bool = False
    publish: Velocity | None = None
    send_goal: Pose2D | None = None


class DriveArbiter:
    """Tracks who drives; see the module docstring."""

    def __init__(self, cancel_retry_s: float = 1.0) -> None:
        self.cancel_retry_s = cancel_retry_s
        #: Key of the last planner goal sent (tasks compare it with their own requests).
        self.nav_key: object | None = None
        #: The last command published moved the robot (a zero must follow before anyone else drives).
        self.moving = False
        self._cancel_sent_s: float | None = None

    def velocity(self, command: Velocity, nav_busy: bool, now_s: float) -> DriveOrders:
        """A task wants to publish ``command`` (clock time ``now_s``)."""
        if nav_busy:
            due = self._cancel_sent_s is None or now_s - self._cancel_sent_s >= self.cancel_retry_s
            if due:
                self._cancel_sent_s = now_s
            return DriveOrders(cancel_nav=due)
        self._cancel_sent_s = None
        self.moving = not command.is_zero
        return DriveOrders(publish=command)

    def navigate(self, request: Navigate) -> DriveOrders:
        """A task wants the planner to take the robot somewhere (a new key sends a new goal)."""
        if request.key == self.nav_key:
            return DriveOrders()
        stop = ZERO if self.moving else None
        self.moving = False
        self.nav_key = request.key
        self._cancel_sent_s = None
        return DriveOrders(publish=stop, send_goal=request.pose)

    def release(self) -> DriveOrders:
        """Nobody drives now (a task ended): leave the robot stopped."""
        if self.moving:
            self.moving = False
            return DriveOrders(publish=ZERO)
        return DriveOrders()
