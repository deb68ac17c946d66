"""Holding the simulated world while the planner works with its robot standing: a plan, a costmap change.

On sim time the simulator paces itself by its drivers (:mod:`services.simulator.pacing`): it waits for a
moving robot's late command, but a robot standing still is waited for by nobody, and a late command only
for a tenth of a wall second. So while the planner computed with its robot stopped (a plan after a
collision ahead, the way through suspected glass after a failed plan, a costmap cleared) the world ran on,
and at 8x a second of such work left the robot standing for 8 simulated seconds: what a docking took
depended on how fast the world ran and how busy the machine was.

The planner announces such work with a :class:`~shared.messages.PacingHold` at the tick it began (the
holder drives next itself: ``until_driven`` false) and lets go once nothing it waits for is left; the
simulator waits for an announced hold up to its own budget (``pacing.hold_wait_max_s``). Off sim time
there is no world to hold and nothing is published. Pure but for the ``publish`` callable it is given.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

from shared.messages import Header, PacingHold

#: The ``holder`` the planner's holds carry (a hold is let go only by its own holder).
HOLDER = "planner"


class WorldHold:
    """One hold for all the planner's reasons: announced when the first begins, let go when the last ends."""

    def __init__(self, publish: Callable[[PacingHold], None], enabled: bool) -> None:
        self._publish = publish
        self._enabled = enabled
        self._reasons: set[str] = set()

    @property
    def reasons(self) -> frozenset[str]:
        """What the planner is at work on now, its robot standing."""
        return frozenset(self._reasons)

    def begin(self, reason: str, tick_s: float) -> None:
        """Work on ``reason`` begins, decided on the tick at ``tick_s`` (sim seconds)."""
        if not self._enabled:
            return
        first = not self._reasons
        self._reasons.add(reason)
        if first:
            self._publish(PacingHold(Header.at(tick_s, ""), holder=HOLDER, hold=True, until_driven=False))

    def end(self, reason: str, tick_s: float) -> None:
        """Work on ``reason`` is done (ending one that never began changes nothing)."""
        if reason not in self._reasons:
            return
        self._reasons.discard(reason)
        if not self._reasons:
            self._let_go(tick_s)

    def end_all(self, tick_s: float) -> None:
        """Nothing is waited for any more (the goal ended, the service stops)."""
        if self._reasons:
            self._reasons.clear()
            self._let_go(tick_s)

    @contextmanager
    def during(self, reason: str, tick_s: float) -> Iterator[None]:
        """Hold the world while the body runs (work done on the calling thread)."""
        self.begin(reason, tick_s)
        try:
            yield
        finally:
            self.end(reason, tick_s)

    def _let_go(self, tick_s: float) -> None:
        self._publish(PacingHold(Header.at(tick_s, ""), holder=HOLDER, hold=False, until_driven=False))


__all__ = ["HOLDER", "WorldHold"]
