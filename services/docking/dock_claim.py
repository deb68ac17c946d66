"""The docking service's side of a shared room: ask the fleet for a dock before driving to one.

A robot sharing docks with others must hold a reservation before it heads for a dock (the fleet service,
``fleet/reserve_dock``). :class:`DockClaim` keeps that conversation's state, without a bus or a clock of
its own: the node asks it when a request is due, sends it, and tells it the answer (or that none came).

- While the robot wants a dock and has none, it asks every ``ask_period_s``; a queued robot waits in
  :class:`AwaitDock`, at the holding pose the fleet gave it (else where it stands).
- While it holds one (docking, charging) it asks every ``renew_period_s``: that renews the claim, tells
  the fleet its charge (a critical robot may have it asked to leave) and, should the fleet have restarted
  and lost its book, claims the dock it stands in again.
- After undocking (or giving up) it releases the dock, asking until the fleet says so.
- When nothing answers for ``patience_s`` the fleet is down: :meth:`DockClaim.fleet_down` says so, and
  the node docks at a dock it can see is free (:func:`docks_seen_free`). What is lost then: two robots
  that cannot see each other's dock may head for the same one; the approach's obstacle stop keeps them
  apart, and the one that finds it taken fails that attempt and tries again.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence

import numpy as np

from services.docking.docking_run import DockRequest
from services.docking.task_io import Intent, Navigate, NavOutcome, Task, TickInputs
from shared.fleet_answer import FleetAnswer
from shared.geometry import Pose2D


class ClaimState(enum.Enum):
    #: Wants no dock (and holds none).
    IDLE = "idle"
    #: Wants a dock: asking, or queued.
    WANTING = "wanting"
    #: Holds ``dock_id``.
    HOLDING = "holding"


class DockClaim:
    """See the module docstring. Times are the node's clock, in seconds."""

    def __init__(
        self, ask_period_s: float = 1.0, renew_period_s: float = 2.0, patience_s: float = 5.0
    ) -> None:
        self.ask_period_s = ask_period_s
        self.renew_period_s = renew_period_s
        self.patience_s = patience_s
        self.state = ClaimState.IDLE
        #: The dock wanted by name ("" : the nearest free one), then the dock held.
        self.dock_id = ""
        self.last_answer: FleetAnswer | None = None
        self.release_pending = False
        self._in_flight = False
        self._sent_s = -math.inf
        self._answered_s = -math.inf
        self._wanting_since_s = math.nan

    # --- what the node does -------------------------------------------------------------------------

    def want(self, now_s: float, dock_id: str = "") -> None:
        """The robot needs a dock (``dock_id`` by name, or "" for the nearest free one)."""
        if self.state is ClaimState.HOLDING and (not dock_id or dock_id == self.dock_id):
            return
        self.state, self.dock_id = ClaimState.WANTING, dock_id
        self.release_pending = False
        self._wanting_since_s = now_s
        self._sent_s = -math.inf

    def holds(self, now_s: float, dock_id: str) -> None:
        """The robot is in ``dock_id`` without having asked (it started there, or docked with the fleet down):
        claim it from now on, so the fleet's book says so."""
        if self.state is not ClaimState.HOLDING or self.dock_id != dock_id:
            self.state, self.dock_id = ClaimState.HOLDING, dock_id
            self.release_pending = False
            self._sent_s = -math.inf
            self._wanting_since_s = now_s

    def drop(self) -> None:
        """The robot left its dock or gave up wanting one: release (asked until the fleet answers)."""
        self.state, self.dock_id, self.last_answer = ClaimState.IDLE, "", None
        self.release_pending = True
        self._sent_s = -math.inf

    def reserve_due(self, now_s: float) -> bool:
        """Whether to send a reservation request now."""
        if self._in_flight or self.state is ClaimState.IDLE:
            return False
        period = self.renew_period_s if self.state is ClaimState.HOLDING else self.ask_period_s
        return now_s - self._sent_s >= period

    def release_due(self, now_s: float) -> bool:
        return self.release_pending and not self._in_flight and now_s - self._sent_s >= self.ask_period_s

    def sent(self, now_s: float) -> None:
        self._in_flight, self._sent_s = True, now_s

    def answered(self, now_s: float, answer: FleetAnswer) -> None:
        """The fleet answered a reservation request."""
        self._in_flight, self._answered_s = False, now_s
        if self.state is ClaimState.IDLE:
            return  # the robot stopped wanting while the request was out: what it may have got is released
        self.last_answer = answer
        if answer.granted:
            self.state, self.dock_id = ClaimState.HOLDING, answer.dock_id

    def released(self, now_s: float) -> None:
        self._in_flight, self._answered_s = False, now_s
        self.release_pending = False

    def unanswered(self, now_s: float) -> None:
        """A request (either kind) got no answer."""
        self._in_flight = False

    # --- what the node reads ------------------------------------------------------------------------

    @property
    def granted_dock(self) -> str | None:
        return self.dock_id if self.state is ClaimState.HOLDING else None

    @property
    def in_flight(self) -> bool:
        return self._in_flight

    def fleet_down(self, now_s: float) -> bool:
        """Wanting a dock, and the fleet has not answered for ``patience_s``."""
        if self.state is not ClaimState.WANTING:
            return False
        heard = max(self._answered_s, self._wanting_since_s)
        return now_s - heard >= self.patience_s

    @property
    def asked_to_leave(self) -> bool:
        return (
            self.state is ClaimState.HOLDING
            and self.last_answer is not None
            and self.last_answer.asked_to_leave
        )


class AwaitPhase(enum.Enum):
    WAITING = "waiting"
    GOING = "going to the holding pose"


class AwaitDock(Task[AwaitPhase]):
    """A robot that needs a dock and has none yet: it waits, at its holding pose when it has one.

    It never finishes by itself: the node replaces it with the docking run once a dock is granted (or
    seen free with the fleet down), and the request and action handle it carries go with it.
    """

    def __init__(self, request: DockRequest) -> None:
        super().__init__(AwaitPhase.WAITING)
        self.request = request
        self.holding_pose: Pose2D | None = None
        self._key: object = None
        self._arrived = False

    @property
    def going(self) -> bool:
        """Driving to the holding pose."""
        return self.holding_pose is not None and not self._arrived

    def state_name(self) -> str:
        return "WAITING_FOR_DOCK"

    @property
    def under_way(self) -> bool:
        return self.going

    @property
    def dock_request(self) -> DockRequest:
        return self.request

    def hold_at(self, pose: Pose2D | None) -> None:
        """The fleet's holding pose for this robot (None: wait where it stands)."""
        if pose is None or (self.holding_pose is not None and pose.distance_to(self.holding_pose) < 0.05):
            return
        self.holding_pose, self._key, self._arrived = pose, self.new_nav_key(), False

    def tick(self, inputs: TickInputs) -> Intent:
        if self.holding_pose is None or self._arrived:
            # Stopped where it is: the planner's goal of the patrol this interrupted is cancelled.
            return self.hold("waiting for a dock")
        if self.phase is not AwaitPhase.GOING:
            self.enter(AwaitPhase.GOING, inputs.now_s)
        outcome = inputs.nav.finished(self._key)
        if outcome is None:
            return Navigate(self.holding_pose, self._key)
        # Arrived, or could not get there: either way the robot waits here now (trying again and again
        # to reach a blocked holding pose would only block others).
        self._arrived = True
        self.enter(AwaitPhase.WAITING, inputs.now_s)
        return self.hold(
            "waiting for a dock"
            if outcome is NavOutcome.SUCCEEDED
            else "waiting for a dock short of the holding pose"
        )


#: A dock counts as taken when this many lidar returns fall within :data:`OCCUPIED_RADIUS_M` of its
#: docking pose: a docked robot's body stands there (the dock's own body is ahead of that pose).
OCCUPIED_MIN_POINTS = 3
OCCUPIED_RADIUS_M = 0.18


def docks_seen_free(
    docks: Sequence[tuple[str, Pose2D]], robot: Pose2D, scan_points_base: np.ndarray | None
) -> list[str]:
    """The docks with no robot seen in them (from the latest lidar scan), nearest first.

    A dock out of the lidar's sight counts as free: this is what the robot can know without the fleet.
    """
    free: list[tuple[float, str]] = []
    for dock_id, pose in docks:
        here = pose.relative_to(robot)
        if scan_points_base is not None and len(scan_points_base):
            near = (
                np.hypot(scan_points_base[:, 0] - here.x, scan_points_base[:, 1] - here.y) < OCCUPIED_RADIUS_M
            )
            if int(np.count_nonzero(near)) >= OCCUPIED_MIN_POINTS:
                continue
        free.append((math.hypot(here.x, here.y), dock_id))
    return [d for _, d in sorted(free)]
