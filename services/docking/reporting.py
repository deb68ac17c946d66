"""What the docking service reports of its task: dock_robot feedback, ``docking/state`` and action results.

A policy of the executive (pure): feedback goes out when its state or retry count changes and at least every
``feedback_period_s`` while it stays the same; the state name on change (with a log line) and every
:data:`STATE_PERIOD_S`; an action's result says whether the task succeeded, its error code and retries.
"""

from __future__ import annotations

import math

from services.docking.events import Effects, Goal, GoalFeedback, Log, PublishState
from services.docking.mission import TaskKind
from services.docking.task_io import Task
from shared.interfaces.docking import DockRobotFeedback, DockRobotResult, UndockRobotResult
from shared.messages import Duration

#: ``docking/state`` is published on change and at least this often.
STATE_PERIOD_S = 1.0


class Reporter:
    """See the module docstring."""

    def __init__(self, feedback_period_s: float) -> None:
        self.feedback_period_s = feedback_period_s
        self._feedback_key: tuple[int, int] | None = None
        self._feedback_published_s = -math.inf
        self._last_state = ""
        self._state_published_s = -math.inf

    def new_task(self) -> None:
        """A task replaced the last one: its first feedback goes out at once."""
        self._feedback_key = None

    def feedback(self, task: Task, goal: Goal | None, now: float, out: Effects) -> None:
        report = task.dock_feedback(now)
        if report is None or goal is None:
            return
        key = (int(report.state), report.num_retries)
        if key == self._feedback_key and now - self._feedback_published_s < self.feedback_period_s:
            return
        self._feedback_key, self._feedback_published_s = key, now
        message = DockRobotFeedback(
            state=int(report.state),
            docking_time=Duration.from_sec(report.docking_time_s),
            num_retries=report.num_retries,
        )
        out.append(GoalFeedback(goal, message))

    def state(self, name: str, now: float, out: Effects) -> None:
        if name == self._last_state and now - self._state_published_s < STATE_PERIOD_S:
            return
        if name != self._last_state:
            out.append(Log.info("state %s (clock %.2f s)", name, now))
        self._last_state, self._state_published_s = name, now
        out.append(PublishState(name))


def result_message(action: TaskKind, task: Task | None) -> DockRobotResult | UndockRobotResult:
    """The action's result for ``task`` (None: a goal cancelled before any task ran for it)."""
    result = task.result if task is not None else None
    success = result is not None and result.success
    code = int(result.error_code) if result is not None else 0
    if action is TaskKind.DOCK:
        return DockRobotResult(success=success, error_code=code, num_retries=task.retries if task else 0)
    return UndockRobotResult(success=success, error_code=code)
