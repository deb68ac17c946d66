"""One driver at a time: the docking service's cmd_vel and the planner's goals never overlap.

Before the service publishes a velocity, the planner must hold no goal: a running goal is cancelled
(the request is repeated every ``cancel_retry_s`` in case it reached the server before the goal did)
and nothing is published until it has ended. Before a goal is sent, the service stops
publishing, after one zero command if the last command it published moved the robot. The node asks
the arbiter for :class:`DriveOrders` and carries them out in order: cancel, publish, send.

Between the two drivers the robot stands, and a simulator paced by its drivers waits for nobody: flat
out, the world ran on while a goal reached the planner and while a cancelled goal ended before the
approach drove, and a docking took longer the faster the world ran. So each handoff holds the world (a
:class:`~shared.messages.PacingHold` at the tick it was decided on): a goal sent, until the planner moves
the robot; a goal cancelled for the service to drive, until the service lets go, which it does once it
publishes again or leaves the robot to nobody (the planner's last commands, still on their way, must not
end that hold).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from services.docking.task_io import Navigate, Velocity
from shared.geometry import Pose2D

ZERO = Velocity(0.0, 0.0)


class Hold(Enum):
    """What a handoff asks of a simulator paced by its drivers (see the module docstring)."""

    #: Hold the world until the next driver (the planner) moves the robot.
    UNTIL_DRIVEN = "until driven"
    #: Hold it until the service lets go (it drives next itself).
    UNTIL_LET_GO = "until let go"
    #: Let go of the service's hold.
    LET_GO = "let go"


@dataclass(frozen=True, slots=True)
class DriveOrders:
    """What the node does this tick: cancel the planner's goal, publish a command, send a goal."""

    cancel_nav: bool = False
    publish: Velocity | None = None
    send_goal: Pose2D | None = None
    #: A handoff's hold from this tick on, or the let-go of one (after the publish).
    hold: Hold | None = None


class DriveArbiter:
    """Tracks who drives; see the module docstring."""

    def __init__(self, cancel_retry_s: float = 1.0) -> None:
        self.cancel_retry_s = cancel_retry_s
        #: Key of the last planner goal sent (tasks compare it with their own requests).
        self.nav_key: object | None = None
        #: The last command published moved the robot (a zero must follow before anyone else drives).
        self.moving = False
        self._cancel_sent_s: float | None = None
        #: A hold for a handoff may still stand (the service lets go when it drives or leaves off).
        self.holding = False

    def velocity(self, command: Velocity, nav_busy: bool, now_s: float) -> DriveOrders:
        """A task wants to publish ``command`` (clock time ``now_s``)."""
        if nav_busy:
            first = self._cancel_sent_s is None
            due = self._cancel_sent_s is None or now_s - self._cancel_sent_s >= self.cancel_retry_s
            if due:
                self._cancel_sent_s = now_s
            if first:
                self.holding = True  # the robot stands until the planner's goal has ended
            return DriveOrders(cancel_nav=due, hold=Hold.UNTIL_LET_GO if first else None)
        self._cancel_sent_s = None
        self.moving = not command.is_zero
        return DriveOrders(publish=command, hold=self._let_go())

    def navigate(self, request: Navigate) -> DriveOrders:
        """A task wants the planner to take the robot somewhere (a new key sends a new goal)."""
        if request.key == self.nav_key:
            return DriveOrders()
        stop = ZERO if self.moving else None
        self.moving = False
        self.nav_key = request.key
        self._cancel_sent_s = None
        self.holding = True  # the robot stands until the planner drives it
        return DriveOrders(publish=stop, send_goal=request.pose, hold=Hold.UNTIL_DRIVEN)

    def release(self) -> DriveOrders:
        """Nobody drives now (a task ended): leave the robot stopped, and the world to run on."""
        let_go = self._let_go()
        if self.moving:
            self.moving = False
            return DriveOrders(publish=ZERO, hold=let_go)
        return DriveOrders(hold=let_go)

    def _let_go(self) -> Hold | None:
        """The let-go of a hold that may still stand, once."""
        let_go = Hold.LET_GO if self.holding else None
        self.holding = False
        return let_go
