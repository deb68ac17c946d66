"""The robot's standing orders: patrol, go home when the battery runs low, carry on once charged.

:class:`Mission` only decides; the node starts the tasks it asks for (the same docking and undocking
runs the actions use). It watches battery_status through :class:`LowBatteryTrigger` (fires when the
charge crosses below the threshold, or on a first reading already below it) and is told what runs now
and how each task ended:

- low battery while idle or patrolling: DOCK (a docking run the action server is not running);
- docked by the mission and charged to ``resume_at``, with patrol waypoints: UNDOCK, then PATROL again
  from the waypoint it was heading to;
- idle, not low, not charging, with patrol waypoints: PATROL;
- a docking the mission started that failed is tried again after ``redock_delay_s`` while the battery
  is still low; what an action asked for is left as it is (no undocking after an explicit dock).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence

from services.docking.seed_controller import LowBatteryTrigger
from shared.geometry import Pose2D


class TaskKind(enum.Enum):
    DOCK = "dock"
    UNDOCK = "undock"
    PATROL = "patrol"


class MissionOrder(enum.Enum):
    DOCK = "dock"
    UNDOCK = "undock"
    PATROL = "patrol"


class MissionMode(enum.Enum):
    #: Free to patrol (when there are waypoints and the battery allows).
    ROAMING = "roaming"
    #: Docked by the mission: charging until ``resume_at``.
    CHARGING = "charging"
    #: An action took over; nothing automatic until an undock or a low battery.
    HOLDING = "holding"


class Mission:
    """See the module docstring. Times are the node's clock, in seconds."""

    def __init__(
        self,
        patrol: Sequence[Pose2D] = (),
        resume_at: float = 0.95,
        low_threshold: float = 0.25,
        auto_dock: bool = True,
        redock_delay_s: float = 30.0,
    ) -> None:
        if not 0.0 < resume_at <= 1.0 or resume_at <= low_threshold:
            raise ValueError(f"resume_at must be in ({low_threshold}, 1], got {resume_at}")
        self.patrol = tuple(patrol)
        self.resume_at = resume_at
        self.trigger = LowBatteryTrigger(low_threshold)
        self.auto_dock = auto_dock
        self.redock_delay_s = redock_delay_s
        self.mode = MissionMode.ROAMING
        self.percentage = math.nan
        self.charging = False
        self.next_waypoint = 0
        self._dock_wanted = False
        self._redock_at_s: float | None = None
        self._leave_asked = False

    def set_auto_dock(self, on: bool) -> None:
        """Switch the battery trigger while running: off drops a docking it wanted and not yet started
        (one already running keeps its way: cancel it as any goal); on while the battery is already low
        and not charging docks at the next decision, as a trigger crossing now would."""
        if on == self.auto_dock:
            return  # set to what it was: nothing to start or drop
        self.auto_dock = on
        if not on:
            self._dock_wanted = False
        elif self.low and not self.charging:
            self._dock_wanted = True

    @property
    def dock_wanted(self) -> bool:
        """Whether the next decision starts a docking (the trigger fired, or auto_dock came on while low)."""
        return self._dock_wanted

    @property
    def low(self) -> bool:
        return math.isfinite(self.percentage) and self.percentage < self.trigger.threshold

    def battery(self, percentage: float, charging: bool) -> bool:
        """Feed a battery reading; True when it should start docking (the trigger fired)."""
        self.charging = charging
        if math.isfinite(percentage):
            self.percentage = percentage
        fired = self.trigger.update(percentage, charging)
        if fired and self.auto_dock:
            self._dock_wanted = True
        return fired

    def leave_dock(self) -> bool:
        """Another robot needs this one's dock (its battery is critical, this one is charged enough):
        undock at the next decision. True when this is news (docked by the mission, not yet asked)."""
        if self.mode is not MissionMode.CHARGING or self._leave_asked:
            return False
        self._leave_asked = True
        return True

    def decide(self, now_s: float, running: TaskKind | None) -> MissionOrder | None:
        """What to start now, given what runs (a docking already running, or any undocking, keeps its way)."""
        if self._dock_wanted:
            self._dock_wanted = False
            if running is None or running is TaskKind.PATROL:
                self._redock_at_s = None
                return MissionOrder.DOCK
        if running is not None:
            return None
        if self._redock_at_s is not None and now_s >= self._redock_at_s:
            self._redock_at_s = None
            if self.auto_dock and self.low and not self.charging:
                return MissionOrder.DOCK
        if self.mode is MissionMode.ROAMING and self.charging:
            self.mode = MissionMode.CHARGING  # started on the dock
        if self._leave_asked and self.mode is MissionMode.CHARGING:
            self._leave_asked = False
            return MissionOrder.UNDOCK
        if not self.patrol:
            return None
        if (
            self.mode is MissionMode.CHARGING
            and math.isfinite(self.percentage)
            and self.percentage >= self.resume_at
        ):
            return MissionOrder.UNDOCK
        if (
            self.mode is MissionMode.ROAMING
            and math.isfinite(self.percentage)
            and not self.low
            and not self.charging
        ):
            return MissionOrder.PATROL
        return None

    def finished(self, kind: TaskKind, success: bool, for_action: bool, now_s: float) -> None:
        """A task ended (or was replaced by another)."""
        if kind is TaskKind.DOCK:
            if for_action:
                self.mode = MissionMode.HOLDING
            elif success:
                self.mode = MissionMode.CHARGING
            else:
                self.mode = MissionMode.ROAMING
                self._redock_at_s = now_s + self.redock_delay_s
        elif kind is TaskKind.UNDOCK:
            self.mode = MissionMode.ROAMING if success else MissionMode.HOLDING
            self._leave_asked = False
