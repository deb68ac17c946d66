"""The traffic rule as a policy of the executive: when this robot gives way to another, where, and for how long.

Pure. Each tick with a task under way it looks at the robots heard lately (:func:`~services.docking.traffic.
must_give_way`); one with priority met on the way makes it give way (:class:`~services.docking.traffic.GiveWay`,
a task the executive runs in place of the one it interrupts, which carries on afterwards). A robot that came
too close is not stopped for again for :data:`~services.docking.traffic.TOO_CLOSE_CALM_S`; one waited for
without the way clearing is left to the planner for :data:`~services.docking.traffic.CARRY_ON_S`.
"""

from __future__ import annotations

import logging

from services.docking.events import Effects, Log
from services.docking.heard import Heard
from services.docking.traffic import (
    CARRY_ON_S,
    TOO_CLOSE_CALM_S,
    GiveWay,
    Meeting,
    Peer,
    must_give_way,
    passing_place,
    plan_points,
    way_ahead,
)
from shared.geometry import Pose2D
from shared.world import Segment


class TrafficPolicy:
    """See the module docstring. ``walls``: the room's, for passing places."""

    def __init__(self, namespace: str, walls: list[Segment]) -> None:
        self.namespace = namespace
        self.walls = walls
        #: Until when not to stop again for a robot that came too close.
        self._calm_until: dict[str, float] = {}
        #: Robots this one waited for lately without the way clearing: left to the planner until then.
        self._carry_on_until: dict[str, float] = {}

    def watch(self, giving_way: GiveWay, heard: Heard) -> None:
        """Tell the give-way task where the robot it waits for is, and what it does."""
        other = next((p for p in heard.peers if p.name == giving_way.peer), None)
        giving_way.peer_seen(
            other.pose if other else None,
            other is not None and other.active,
            other is not None and other.giving_way,
        )

    def meet(self, heard: Heard, resume: object | None, out: Effects) -> GiveWay | None:
        """The give-way to run now (interrupting a task that would ``resume``), or None."""
        now = heard.now_s
        if heard.battery is None or heard.latest_pose is None:
            return None
        me = heard.latest_pose
        calm = {peer for peer, until in self._calm_until.items() if now < until}
        carry_on = {peer for peer, until in self._carry_on_until.items() if now < until}
        own_plan = heard.own_plan  # decoded only for a robot met face to face
        met = must_give_way(
            me, self.namespace, heard.battery, list(heard.peers), self.walls, calm, carry_on, own_plan
        )
        if met is None:
            return None
        peer, meeting = met
        place = self._place(me, peer, meeting, now, out)
        own_way = way_ahead(me, plan_points(own_plan)) if meeting is Meeting.HEAD_ON_PRIORITY else None
        return GiveWay(peer, meeting, place, resume, own_way)

    def gave_way(self, giving_way: GiveWay, now: float, out: Effects) -> None:
        """The give-way ended well: say so, and leave an unresolved meeting to the planner for a while."""
        out.append(Log.info("gave way: %s", giving_way.message or "done"))
        if giving_way.unresolved:
            self._carry_on_until[giving_way.peer] = now + CARRY_ON_S

    def _place(self, me: Pose2D, peer: Peer, meeting: Meeting, now: float, out: Effects) -> Pose2D | None:
        """Where to give way (None: stop where it stands), saying why in the log."""
        place: Pose2D | None = None
        if meeting is Meeting.HEAD_ON:
            place = passing_place(me, peer, self.walls)
            if place is None:
                out.append(
                    Log.now_and_then(
                        logging.WARNING,
                        "no-passing-place",
                        "met %s head-on and must give way, but found no passing place: stopping",
                        peer.name,
                    )
                )
        if place is not None:
            out.append(
                Log.info(
                    "met %s head-on (it has priority): giving way at (%.2f, %.2f)",
                    peer.name,
                    place.x,
                    place.y,
                )
            )
        elif meeting is Meeting.HEAD_ON_PRIORITY:
            out.append(
                Log.info("met %s head-on (this robot has priority): waiting for it to back out", peer.name)
            )
        elif meeting is Meeting.TOO_CLOSE:
            out.append(Log.info("%s is too close in front: stopping for a moment", peer.name))
            self._calm_until[peer.name] = now + TOO_CLOSE_CALM_S
        else:
            out.append(Log.info("%s crosses this robot's way (it has priority): stopping for it", peer.name))
        return place
