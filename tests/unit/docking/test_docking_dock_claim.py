"""Sharing docks: the docking service's reservation conversation, waiting for a dock, and docks seen free."""

from __future__ import annotations

import math

import numpy as np

from services.docking.dock_claim import AwaitDock, ClaimState, DockClaim, docks_seen_free
from services.docking.docking_run import DockRequest
from services.docking.mission import Mission, MissionMode, MissionOrder, TaskKind
from services.docking.task_io import STOP, Navigate, NavOutcome, NavStatus, TickInputs
from shared.fleet_answer import FleetAnswer
from shared.geometry import Pose2D


def test_a_claim_asks_each_period_while_wanting_and_renews_more_slowly_while_holding() -> None:
    claim = DockClaim(ask_period_s=1.0, renew_period_s=2.0, patience_s=5.0)
    assert not claim.reserve_due(0.0), "wants nothing yet"
    claim.want(0.0)
    assert claim.reserve_due(0.0)
    claim.sent(0.0)
    assert not claim.reserve_due(3.0), "one request at a time"
    claim.answered(0.1, FleetAnswer(False, queue_position=1, reason="every dock is taken"))
    assert claim.state is ClaimState.WANTING and claim.granted_dock is None
    assert not claim.reserve_due(0.5) and claim.reserve_due(1.0)
    claim.sent(1.0)
    claim.answered(1.1, FleetAnswer(True, "west"))
    assert claim.granted_dock == "west"
    assert not claim.reserve_due(2.5) and claim.reserve_due(3.0), "renewed every 2 s"
    claim.want(3.0)
    assert claim.granted_dock == "west", "wanting again while holding keeps the dock"


def test_a_dropped_claim_is_released_until_the_fleet_answers_and_a_late_grant_is_not_taken() -> None:
    claim = DockClaim()
    claim.want(0.0)
    claim.sent(0.0)
    claim.drop()
    claim.answered(0.2, FleetAnswer(True, "west"))
    assert claim.granted_dock is None, "stopped wanting while asking"
    assert claim.release_due(1.0)
    claim.sent(1.0)
    claim.unanswered(2.0)
    assert claim.release_due(2.0), "asked again"
    claim.sent(2.0)
    claim.released(2.1)
    assert not claim.release_due(10.0) and not claim.reserve_due(10.0)


def test_the_fleet_is_down_after_the_patience_without_an_answer() -> None:
    claim = DockClaim(patience_s=5.0)
    claim.want(10.0)
    claim.sent(10.0)
    claim.unanswered(11.0)
    assert not claim.fleet_down(14.9) and claim.fleet_down(15.0)
    claim.answered(15.5, FleetAnswer(False, queue_position=2))
    assert not claim.fleet_down(20.0), "an answer, even a queue place, means the fleet is up"
    claim.holds(21.0, "east")
    assert not claim.fleet_down(100.0) and claim.granted_dock == "east"


def test_asked_to_leave_only_while_holding() -> None:
    claim = DockClaim()
    claim.want(0.0)
    claim.sent(0.0)
    claim.answered(0.1, FleetAnswer(True, "west"))
    claim.sent(2.0)
    claim.answered(2.1, FleetAnswer(True, "west", asked_to_leave=True))
    assert claim.asked_to_leave
    claim.drop()
    assert not claim.asked_to_leave


def _inputs(now: float, nav: NavStatus | None = None) -> TickInputs:
    return TickInputs(now_s=now, robot_pose=Pose2D(1.0, 1.0, 0.0), nav=nav or NavStatus())


def test_await_dock_holds_still_then_goes_to_its_holding_pose_once_and_waits_there() -> None:
    task = AwaitDock(DockRequest())
    assert task.step(_inputs(0.0)) == STOP and task.holding == "waiting for a dock"
    task.hold_at(Pose2D(5.0, 1.0, 0.0))
    intent = task.step(_inputs(0.1))
    assert isinstance(intent, Navigate) and intent.pose == Pose2D(5.0, 1.0, 0.0)
    assert task.step(_inputs(0.2, NavStatus(intent.key, busy=True))) == intent
    assert task.step(_inputs(3.0, NavStatus(intent.key, outcome=NavOutcome.SUCCEEDED))) == STOP
    task.hold_at(Pose2D(5.0, 1.0, 0.0))
    assert task.step(_inputs(3.1, NavStatus(intent.key, outcome=NavOutcome.SUCCEEDED))) == STOP, (
        "no second trip"
    )
    assert task.result is None, "waiting never ends by itself"


def test_a_dock_with_a_robot_in_it_is_not_seen_free() -> None:
    robot = Pose2D(0.0, 0.0, 0.0)
    docks = [("near", Pose2D(2.0, 0.0, 0.0)), ("far", Pose2D(0.0, 5.0, math.pi / 2))]
    assert docks_seen_free(docks, robot, None) == ["near", "far"]
    body = np.array([[1.9, -0.1], [1.9, 0.0], [1.9, 0.1], [1.85, 0.12]])  # a robot's back seen in "near"
    assert docks_seen_free(docks, robot, body) == ["far"]
    assert docks_seen_free(docks, robot, body[:2]) == ["near", "far"], "two stray returns are not a robot"


def test_the_mission_leaves_its_dock_when_asked_only_while_charging_after_its_own_docking() -> None:
    mission = Mission([Pose2D(1.0, 1.0, 0.0)], resume_at=0.9)
    assert not mission.leave_dock(), "not docked"
    mission.battery(0.2, False)
    assert mission.decide(0.0, None) is MissionOrder.DOCK
    mission.finished(TaskKind.DOCK, True, False, 1.0)
    mission.battery(0.7, True)
    assert mission.mode is MissionMode.CHARGING and mission.decide(2.0, None) is None
    assert mission.leave_dock() and not mission.leave_dock(), "news once"
    assert mission.decide(3.0, None) is MissionOrder.UNDOCK, "below resume_at, but asked"
    mission.finished(TaskKind.UNDOCK, True, False, 4.0)
    mission.battery(0.69, False)
    assert mission.decide(5.0, None) is MissionOrder.PATROL


def test_a_fleet_answer_reads_the_response_and_its_holding_pose() -> None:
    from shared.interfaces.fleet import ReserveDockResponse

    queued = FleetAnswer.from_response(
        ReserveDockResponse(
            queue_position=2, reason="every dock is taken", holding_pose=np.array([4.0, 7.4, 0.0])
        )
    )
    assert not queued.granted and not queued.refused and queued.holding_pose == Pose2D(4.0, 7.4, 0.0)
    refused = FleetAnswer.from_response(
        ReserveDockResponse(reason="no dock 'x'", holding_pose=np.array([1.0, np.nan, 0.0]))
    )
    assert refused.refused and refused.holding_pose is None
    assert FleetAnswer.from_response(ReserveDockResponse(granted=True, dock_id="west")).dock_id == "west"
