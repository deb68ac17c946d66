"""Patrolling: the planner takes the robot round a loop of waypoints until something more urgent comes.

Each waypoint is one planner goal; the next one is sent when it ends. A failed goal is not retried at
once: the patrol waits ``retry_delay_s`` and moves on to the next waypoint. It never finishes by
itself; the mission cancels (or replaces) it, and resumes later from :attr:`Patrol.next_index`.
"""

from __future__ import annotations

import enum
import logging
from collections.abc import Sequence

from services.docking.task_io import Intent, Navigate, NavOutcome, Task, TickInputs
from shared.geometry import Pose2D

log = logging.getLogger(__name__)


class PatrolPhase(enum.Enum):
    GOING = "going"
    PAUSED = "paused"


class Patrol(Task[PatrolPhase]):
    def __init__(self, waypoints: Sequence[Pose2D], start_index: int = 0, retry_delay_s: float = 2.0) -> None:
        if not waypoints:
            raise ValueError("a patrol needs at least one waypoint")
        super().__init__(PatrolPhase.GOING)
        self.waypoints = tuple(waypoints)
        self.next_index = start_index % len(self.waypoints)
        self.retry_delay_s = retry_delay_s
        self.laps = 0
        self._key: object = self.new_nav_key()

    def state_name(self) -> str:
        return "PATROLLING"

    @property
    def under_way(self) -> bool:
        return True

    @property
    def waypoint_index(self) -> int:
        return self.next_index

    @property
    def current_goal(self) -> Pose2D:
        return self.waypoints[self.next_index]

    def _advance(self) -> None:
        self.next_index = (self.next_index + 1) % len(self.waypoints)
        if self.next_index == 0:
            self.laps += 1
        self._key = self.new_nav_key()

    def tick(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        if self.phase is PatrolPhase.PAUSED:
            if self.phase_time_s(now) < self.retry_delay_s:
                return None
            self._advance()
            self.enter(PatrolPhase.GOING, now)
        outcome = inputs.nav.finished(self._key)
        if outcome is None:
            return Navigate(self.current_goal, self._key)
        if outcome is NavOutcome.SUCCEEDED:
            self._advance()
            return Navigate(self.current_goal, self._key)
        log.warning(
            "patrol waypoint %d %s (%s); moving on in %g s",
            self.next_index,
            outcome.value,
            inputs.nav.reason or "no reason given",
            self.retry_delay_s,
        )
        self.enter(PatrolPhase.PAUSED, now)
        return None
