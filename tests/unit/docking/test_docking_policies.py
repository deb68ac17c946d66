"""The executive's policies on their own: what it reports (feedback, state, results) and the traffic rule."""

from __future__ import annotations

import math
from pathlib import Path

from services.docking.events import Effects, Goal, GoalFeedback, Log, PublishState
from services.docking.heard import Heard
from services.docking.mission import TaskKind
from services.docking.reporting import STATE_PERIOD_S, Reporter, result_message
from services.docking.task_io import DockFeedback, Intent, Task, TickInputs
from services.docking.traffic import GiveWay, Meeting, Peer
from services.docking.traffic_policy import TrafficPolicy
from shared.geometry import Pose2D
from shared.interfaces.docking import DockRobotResult, UndockRobotResult
from shared.world import load_world

CORRIDOR = Path(__file__).resolve().parents[3] / "deploy" / "worlds" / "fleet" / "corridor_meeting.yaml"


class _Docking(Task):
    """A task that reports feedback in ``state`` with ``retries``."""

    def __init__(self) -> None:
        self.state, self.retries_now = 1, 0

    def tick(self, inputs: TickInputs) -> Intent:
        raise AssertionError("the reporter never steps a task")

    def dock_feedback(self, now_s: float) -> DockFeedback | None:
        return DockFeedback(self.state, self.retries_now, now_s)  # type: ignore[arg-type]


def _feedback(effects: Effects) -> list[int]:
    return [e.feedback.state for e in effects if isinstance(e, GoalFeedback)]


def test_feedback_goes_out_on_a_change_and_every_period_while_it_stays() -> None:
    reporter, task, goal = Reporter(feedback_period_s=0.5), _Docking(), Goal(object(), TaskKind.DOCK)
    out: Effects = []
    reporter.feedback(task, goal, 0.0, out)
    reporter.feedback(task, goal, 0.2, out)
    assert _feedback(out) == [1], "the same state within the period is not sent again"
    task.state = 2
    reporter.feedback(task, goal, 0.3, out)
    reporter.feedback(task, goal, 0.9, out)
    assert _feedback(out) == [1, 2, 2]
    reporter.new_task()
    reporter.feedback(task, goal, 0.95, out)
    assert _feedback(out) == [1, 2, 2, 2], "a new task's first feedback goes out at once"
    reporter.feedback(task, None, 2.0, out)
    assert len(_feedback(out)) == 4, "no goal, no feedback"


def test_the_state_is_published_on_change_with_a_log_line_and_every_period() -> None:
    reporter, out = Reporter(0.5), []  # type: ignore[var-annotated]
    reporter.state("IDLE", 0.0, out)
    reporter.state("IDLE", STATE_PERIOD_S / 2, out)
    reporter.state("IDLE", STATE_PERIOD_S, out)
    reporter.state("DOCKING", STATE_PERIOD_S + 0.01, out)
    assert [e.name for e in out if isinstance(e, PublishState)] == ["IDLE", "IDLE", "DOCKING"]
    assert [e.text() for e in out if isinstance(e, Log)] == [
        "state IDLE (clock 0.00 s)",
        "state DOCKING (clock 1.01 s)",
    ]


def test_a_goal_cancelled_before_any_task_gets_a_failed_result_of_its_action() -> None:
    assert result_message(TaskKind.DOCK, None) == DockRobotResult(success=False)
    assert result_message(TaskKind.UNDOCK, None) == UndockRobotResult(success=False)


def _heard(now_s: float, me: Pose2D, *peers: Peer) -> Heard:
    return Heard(now_s=now_s, latest_pose=me, robot_pose=me, battery=0.8, peers=peers)


def _corridor_policy() -> TrafficPolicy:
    room = load_world(str(CORRIDOR))
    return TrafficPolicy("r1", [*room.opaque_segments(), *room.glass])


def test_a_robot_with_priority_met_head_on_makes_this_one_give_way_and_says_where() -> None:
    policy, me = _corridor_policy(), Pose2D(3.5, 3.0, 0.0)
    out: Effects = []
    assert policy.meet(_heard(0.0, me), None, out) is None and out == [], "nobody met"
    other = Peer("r2", Pose2D(6.0, 3.0, math.pi), 0.4, True)  # lower charge: it has priority
    giving_way = policy.meet(_heard(0.05, me, other), "resume me", out)
    assert isinstance(giving_way, GiveWay) and giving_way.peer == "r2" and giving_way.resume == "resume me"
    assert giving_way.meeting is Meeting.HEAD_ON
    assert any("met r2 head-on (it has priority)" in e.text() for e in out if isinstance(e, Log))


def test_a_meeting_left_unresolved_is_left_to_the_planner_for_a_while() -> None:
    policy, me = _corridor_policy(), Pose2D(3.5, 3.0, 0.0)
    other = Peer("r2", Pose2D(6.0, 3.0, math.pi), 0.4, True)
    out: Effects = []
    giving_way = policy.meet(_heard(0.0, me, other), None, out)
    assert giving_way is not None
    giving_way.unresolved = True
    policy.gave_way(giving_way, 1.0, out)
    assert policy.meet(_heard(1.1, me, other), None, out) is None, "carrying on past r2 for a while"
