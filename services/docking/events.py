r"""What happens to the docking executive (events) and what it asks the node to do (effects): plain data.

The node turns action goals, cancels, the fleet's answers and dock sightings into :data:`Event`\ s, and
carries out the :data:`Effects` the executive and its policies answer with, in order: drive orders, fleet
requests, action feedback and results, the state to publish, and the log lines (:class:`Log`: the
executive writes no log itself, so it is tested by what it says).
"""

from __future__ import annotations

import logging

import msgspec

from services.docking.docking_run import DockRequest
from services.docking.drive_arbiter import DriveOrders
from services.docking.heard import DockSighting
from services.docking.mission import TaskKind
from services.docking.task_io import Outcome
from shared.fleet_answer import FleetAnswer
from shared.interfaces.docking import DockRobotFeedback, DockRobotResult, UndockRobotResult


class Goal(msgspec.Struct, frozen=True, eq=False):
    """An action goal being served: the node's ``handle`` (opaque here: one per goal, compared by identity)
    and which action it belongs to."""

    handle: object
    action: TaskKind

    def same(self, other: Goal | None) -> bool:
        return other is not None and other.handle is self.handle


# --- events: what happens ------------------------------------------------------------------------------


class DockGoal(msgspec.Struct, frozen=True):
    goal: Goal
    request: DockRequest


class UndockGoal(msgspec.Struct, frozen=True):
    goal: Goal
    max_time_s: float
    dock_type: str = ""


class CancelGoal(msgspec.Struct, frozen=True):
    goal: Goal


class FleetReserved(msgspec.Struct, frozen=True):
    """The fleet's answer to a reservation request (None and an error: it did not answer)."""

    answer: FleetAnswer | None
    error: Exception | None = None


class FleetReleased(msgspec.Struct, frozen=True):
    """The fleet's answer to a release: the dock released ("" none), or None and an error."""

    dock_id: str | None
    error: Exception | None = None


Event = DockGoal | UndockGoal | CancelGoal | FleetReserved | FleetReleased | DockSighting


# --- effects: what the node does -----------------------------------------------------------------------


class Drive(msgspec.Struct, frozen=True):
    orders: DriveOrders


class Reserve(msgspec.Struct, frozen=True):
    """Ask the fleet for ``dock_id`` ("" : the nearest free one by ``path_lengths``) at charge ``battery``."""

    battery: float
    dock_id: str
    path_lengths: dict[str, float] | None


class Release(msgspec.Struct, frozen=True):
    """Tell the fleet the robot's dock is free."""


class WantDetections(msgspec.Struct, frozen=True):
    """Whether the running task wants dock detections (the subscription follows at once)."""

    wanted: bool


class GoalFeedback(msgspec.Struct, frozen=True):
    goal: Goal
    feedback: DockRobotFeedback


class GoalEnded(msgspec.Struct, frozen=True):
    """Answer ``goal`` (if its client still waits) with ``result``, as succeeded, canceled or aborted."""

    goal: Goal
    outcome: Outcome
    result: DockRobotResult | UndockRobotResult


class PublishState(msgspec.Struct, frozen=True):
    name: str


class Log(msgspec.Struct, frozen=True):
    """A line for the service's log: ``fmt % args`` at ``level``; with a ``key``, at most one line per key
    every few seconds (a condition that lasts is said once, not at every tick)."""

    level: int
    fmt: str
    args: tuple[object, ...] = ()
    key: str | None = None

    @classmethod
    def info(cls, fmt: str, *args: object) -> Log:
        return cls(logging.INFO, fmt, args)

    @classmethod
    def warning(cls, fmt: str, *args: object) -> Log:
        return cls(logging.WARNING, fmt, args)

    @classmethod
    def now_and_then(cls, level: int, key: str, fmt: str, *args: object) -> Log:
        return cls(level, fmt, args, key)

    def text(self) -> str:
        return self.fmt % self.args if self.args else self.fmt


Effect = Drive | Reserve | Release | WantDetections | GoalFeedback | GoalEnded | PublishState | Log
Effects = list[Effect]
