"""The one task the docking service runs: starting it, replacing it, ending it, and what each says.

A policy of the executive (pure). A task started replaces the running one: the replaced task's action goal
is answered as cancelled, and a patrol it was on carries its next waypoint over to the mission. A task ends
when it says so: the slot is cleared and its outcome logged (a failure as a warning), and its action goal
is answered with its result. The two tasks the executive starts for reasons of its own are kept by name:
waiting for a dock the fleet has not granted yet, and giving way to another robot, whose end resumes what
it interrupted instead of ending the mission's docking.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from services.docking.dock_claim import AwaitDock
from services.docking.events import Effects, Goal, GoalEnded, Log
from services.docking.mission import Mission, TaskKind
from services.docking.reporting import result_message
from services.docking.task_io import Outcome, Task, TaskResult
from services.docking.traffic import GiveWay


@dataclass(frozen=True)
class Ended:
    """A task that has just ended: what it was for and how it went."""

    task: Task
    kind: TaskKind
    goal: Goal | None
    result: TaskResult
    #: The give-way this was (it resumes what it interrupted); None for any other task.
    gave_way: GiveWay | None


class TaskLife:
    """See the module docstring."""

    def __init__(self, mission: Mission) -> None:
        self.mission = mission
        self.task: Task | None = None
        self.kind: TaskKind | None = None
        self.goal: Goal | None = None
        #: The running task when it waits for the fleet to grant a dock.
        self.awaiting: AwaitDock | None = None
        #: The running task when it gives way to another robot.
        self.giving_way: GiveWay | None = None
        #: What the running task last said it holds still for ("" when it drives).
        self._holding = ""

    def start(self, task: Task, kind: TaskKind, goal: Goal | None, out: Effects) -> Task | None:
        """Run ``task`` from the next tick on; returns the task it replaced when that one was waiting for a
        dock (the executive then lets go of its claim unless the new task docks). An :class:`AwaitDock` or
        a :class:`GiveWay` is one of the executive's own, and is kept by name."""
        old, old_goal = self.task, self.goal
        if old is not None and old.waypoint_index is not None:
            self.mission.next_waypoint = old.waypoint_index
        if old_goal is not None and not old_goal.same(goal):
            out.append(GoalEnded(old_goal, Outcome.CANCELED, result_message(old_goal.action, None)))
        if old is not None:
            out.append(Log.info("%s replaced by %s", type(old).__name__, type(task).__name__))
        was_awaiting = old if old is not None and old is self.awaiting else None
        self.task, self.kind, self.goal = task, kind, goal
        self.awaiting = task if isinstance(task, AwaitDock) else None
        self.giving_way = task if isinstance(task, GiveWay) else None
        return was_awaiting

    def holds(self, task: Task, out: Effects) -> None:
        """Say (now and then) why the running task holds still, when that changes."""
        if task.holding and task.holding != self._holding:
            out.append(
                Log.now_and_then(logging.INFO, f"hold:{task.holding}", "holding still: %s", task.holding)
            )
        self._holding = task.holding

    def end(self, now_s: float, out: Effects) -> Ended:
        """The running task has ended (``task.done``): clear the slot and report its outcome. A give-way's
        end is the executive's to act on (it resumes the interrupted docking), so it is reported only there."""
        task, kind, goal = self.task, self.kind, self.goal
        assert task is not None and task.result is not None and kind is not None
        result = task.result
        gave_way = self.giving_way if task is self.giving_way else None
        self.task, self.kind, self.goal = None, None, None
        self.awaiting = self.giving_way = None
        self._holding = ""
        if task.waypoint_index is not None:
            self.mission.next_waypoint = task.waypoint_index
        ended = Ended(task, kind, goal, result, gave_way)
        if gave_way is not None and result.success:
            return ended
        level = logging.INFO if result.outcome is not Outcome.FAILED else logging.WARNING
        feedback = task.dock_feedback(now_s)
        took = f" after {feedback.docking_time_s:.1f} s" if feedback is not None else ""
        out.append(
            Log(
                level,
                "%s %s%s (code %d, %d retries)%s",
                (
                    kind.value,
                    result.outcome.value,
                    took,
                    int(result.error_code),
                    result.num_retries,
                    f": {result.message}" if result.message else "",
                ),
            )
        )
        if goal is not None:
            out.append(GoalEnded(goal, result.outcome, result_message(goal.action, task)))
        return ended
