"""The task-life policy alone: what starting, replacing and ending a task says and answers."""

from __future__ import annotations

import logging

from services.docking.dock_claim import AwaitDock
from services.docking.docking_run import DockRequest
from services.docking.errors import DockingErrorCode
from services.docking.events import Effects, Goal, GoalEnded, Log
from services.docking.mission import Mission, TaskKind
from services.docking.patrol import Patrol
from services.docking.task_io import Outcome, TaskResult
from services.docking.task_life import TaskLife
from services.docking.traffic import GiveWay, Meeting, Peer
from shared.geometry import Pose2D


def _give_way(resume: object) -> GiveWay:
    peer = Peer("r1", Pose2D(1.0, 0.0, 3.1), battery=0.2, under_way=True)
    return GiveWay(peer, Meeting.CROSSING, place=None, resume=resume)


def test_a_task_started_over_another_cancels_its_goal_and_keeps_the_patrol_where_it_was() -> None:
    mission = Mission([Pose2D(0.0, 0.0, 0.0), Pose2D(1.0, 0.0, 0.0), Pose2D(2.0, 0.0, 0.0)])
    life = TaskLife(mission)
    out: Effects = []
    patrol = Patrol(mission.patrol, start_index=2)
    assert life.start(patrol, TaskKind.PATROL, None, out) is None
    assert out == [] and life.task is patrol and life.kind is TaskKind.PATROL
    goal = Goal(object(), TaskKind.DOCK)
    waiting = AwaitDock(DockRequest())
    assert life.start(waiting, TaskKind.DOCK, goal, out) is None
    assert mission.next_waypoint == 2, "the patrol picks up at the waypoint it was going to"
    assert [e.text() for e in out if isinstance(e, Log)] == ["Patrol replaced by AwaitDock"]
    assert life.awaiting is waiting and life.goal is goal
    # a new goal over the waiting one: its goal is answered as cancelled, and the caller learns it waited
    out.clear()
    undock = Goal(object(), TaskKind.UNDOCK)
    assert life.start(Patrol(mission.patrol), TaskKind.UNDOCK, undock, out) is waiting
    (ended,) = [e for e in out if isinstance(e, GoalEnded)]
    assert ended.goal is goal and ended.outcome is Outcome.CANCELED
    assert life.awaiting is None


def test_the_same_goal_carried_into_the_next_task_is_not_answered() -> None:
    life = TaskLife(Mission())
    goal = Goal(object(), TaskKind.DOCK)
    out: Effects = []
    life.start(AwaitDock(DockRequest()), TaskKind.DOCK, goal, out)
    life.start(AwaitDock(DockRequest(dock_id="home")), TaskKind.DOCK, goal, out)
    assert not [e for e in out if isinstance(e, GoalEnded)]


def test_a_failed_task_ends_with_a_warning_and_its_goal_answered() -> None:
    life = TaskLife(Mission())
    goal = Goal(object(), TaskKind.DOCK)
    task = AwaitDock(DockRequest())
    life.start(task, TaskKind.DOCK, goal, [])
    task.result = TaskResult(Outcome.FAILED, DockingErrorCode.FAILED_TO_STAGE, 2, "boxed in")
    out: Effects = []
    ended = life.end(5.0, out)
    assert (ended.task, ended.kind, ended.goal, ended.gave_way) == (task, TaskKind.DOCK, goal, None)
    assert life.task is None and life.kind is None and life.goal is None
    (line,) = [e for e in out if isinstance(e, Log)]
    assert line.level == logging.WARNING
    assert line.text() == "dock failed (code 903, 2 retries): boxed in"
    (answered,) = [e for e in out if isinstance(e, GoalEnded)]
    assert answered.goal is goal and answered.outcome is Outcome.FAILED


def test_a_give_way_that_cleared_ends_quietly_for_the_executive_to_resume() -> None:
    life = TaskLife(Mission())
    goal = Goal(object(), TaskKind.DOCK)
    request = DockRequest(dock_id="home")
    giving_way = _give_way(request)
    life.start(giving_way, TaskKind.DOCK, goal, [])
    giving_way.result = TaskResult(Outcome.SUCCEEDED)
    out: Effects = []
    ended = life.end(1.0, out)
    assert ended.gave_way is giving_way and ended.goal is goal and ended.gave_way.resume is request
    assert out == [], "the goal carries on with the resumed docking: nothing is answered or logged"
    # cancelled instead: it ends what it interrupted, answered like any other task
    again = _give_way(request)
    life.start(again, TaskKind.DOCK, goal, [])
    again.result = TaskResult(Outcome.CANCELED)
    out.clear()
    assert life.end(2.0, out).gave_way is again
    assert [e.outcome for e in out if isinstance(e, GoalEnded)] == [Outcome.CANCELED]


def test_why_a_task_holds_still_is_said_once_per_change() -> None:
    life = TaskLife(Mission())
    task = AwaitDock(DockRequest())
    life.start(task, TaskKind.DOCK, None, [])
    out: Effects = []
    task.holding = "waiting for a dock"
    life.holds(task, out)
    life.holds(task, out)
    task.holding = ""
    life.holds(task, out)
    task.holding = "waiting for a dock"
    life.holds(task, out)
    assert [e.text() for e in out if isinstance(e, Log)] == ["holding still: waiting for a dock"] * 2
