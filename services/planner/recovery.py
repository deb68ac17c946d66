"""What a recovery forgets of the glass memory.

A recovery backs up (:class:`services.planner.behaviors.DriveStraight` in reverse, the ``backup``
behaviour's motion), then clears the costmap round the robot and replans. When the clearing forgot glass
the sonar had heard, the robot first turns once in place
(:meth:`~services.planner.params.Params.recovery_look_around`): the sonar looks forward only, and without
the turn robots replanned at once through the panes they had just forgotten and drove into them (see the
generated glass rooms in docs/measurements).
"""

from __future__ import annotations

import enum


class GlassClearing(enum.Enum):
    """How much of the glass memory a recovery forgets."""

    KEEP = "keep"
    AROUND_ROBOT = "around_robot"
    ALL = "all"


def glass_clearing(recovery: int, planning_failed: bool) -> GlassClearing:
    """What recovery number ``recovery`` (1, 2, ...) forgets of the glass memory.

    Glass is known only from the forward-looking sonar and cannot be seen again from beside it, so odd
    recoveries keep it; even ones forget it round the robot, in case a spurious echo is what blocks the way
    (glass farther off stays: forgetting a pane's end the sonar saw once, a robot replanned past it and
    drove into it; so does glass within the robot's turning reach, which a stuck robot beside a pane
    otherwise met next). When the planner still finds no path after that, from the fourth recovery on, the
    glass that blocks it may lie anywhere: all of it is forgotten, as Nav2 clears its whole global
    costmap when computing a path fails.
    """
    if recovery % 2 == 1:
        return GlassClearing.KEEP
    if planning_failed and recovery >= 4:
        return GlassClearing.ALL
    return GlassClearing.AROUND_ROBOT
