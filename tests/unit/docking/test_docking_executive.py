"""The docking executive without a bus: the mission, task life and action results, the fleet's dock
claim and the traffic rule, driven by snapshots and events and judged by the effects it returns."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from services.docking.dock_db import load_dock_db
from services.docking.docking_run import DockRequest
from services.docking.events import (
    CancelGoal,
    DockGoal,
    Drive,
    Effects,
    FleetReleased,
    FleetReserved,
    Goal,
    GoalEnded,
    GoalFeedback,
    Log,
    PublishState,
    Release,
    Reserve,
    UndockGoal,
    WantDetections,
)
from services.docking.executive import Executive
from services.docking.heard import Heard, NavHeard
from services.docking.mission import TaskKind
from services.docking.params import Params
from services.docking.safety import LidarReturns
from services.docking.task_io import Outcome
from services.docking.traffic import Peer
from shared.fleet_answer import FleetAnswer
from shared.geometry import Pose2D
from shared.interfaces.docking import DockRobotResult, UndockRobotResult
from shared.world import load_world

WORLDS = Path(__file__).resolve().parents[3] / "deploy" / "worlds"
SEED_ROOM = WORLDS / "seed_room.yaml"
CORRIDOR = WORLDS / "fleet" / "corridor_meeting.yaml"


def _acts(effects: Effects) -> Effects:
    """What the node does, without the log lines."""
    return [e for e in effects if not isinstance(e, Log)]


def _said(effects: Effects) -> list[str]:
    """The log lines among ``effects``."""
    return [e.text() for e in effects if isinstance(e, Log)]


def _executive(world: Path = SEED_ROOM, namespace: str = "", **params: object) -> Executive:
    p = Params(dock_database=str(world), **params)
    room = load_world(str(world)) if p.fleet or not p.patrol else None
    return Executive(p, load_dock_db(p.dock_database), room, namespace)


SOMEWHERE = Pose2D(1.0, 1.0, 0.0)


def _heard(now_s: float, pose: Pose2D | None = SOMEWHERE, **fields: object) -> Heard:
    return Heard(now_s=now_s, latest_pose=pose, robot_pose=pose, **fields)  # type: ignore[arg-type]


def _of(effects: Effects, kind: type) -> list:
    return [e for e in effects if isinstance(e, kind)]


def _states(effects: Effects) -> list[str]:
    return [e.name for e in _of(effects, PublishState)]


def test_idle_it_publishes_its_state_on_change_and_every_second() -> None:
    ex = _executive()
    assert _states(ex.step(_heard(0.0))) == ["IDLE"]
    assert _states(ex.step(_heard(0.5))) == [], "no change, within the second"
    assert _states(ex.step(_heard(1.0))) == ["IDLE"]
    assert _states(ex.step(_heard(1.05, charging=True))) == ["DOCKED"], "a change is published at once"


def test_a_low_battery_starts_a_docking_run_that_asks_for_detections_from_the_staging_pose() -> None:
    ex = _executive()
    ex.battery_reading(0.2, False)
    dock = next(iter(ex.database)).pose2d
    staging = dock.compose(Pose2D(-0.7, 0.0, 0.0))  # at the staging pose, facing the marker
    effects = ex.step(_heard(0.0, staging, battery=0.2))
    assert ex.task is not None and ex.life.kind is TaskKind.DOCK and ex.life.goal is None
    assert _of(effects, WantDetections) == [WantDetections(False)], "no dock chosen before its first step"
    for t in (0.05, 0.1, 0.15):
        wanted = _of(ex.step(_heard(t, staging, battery=0.2)), WantDetections)
    assert wanted == [WantDetections(True)], "at the staging pose the approach looks for the marker"
    assert _of(_executive().step(_heard(0.0, staging)), WantDetections) == [WantDetections(False)]
    assert _states(effects) and _states(effects)[0] not in ("IDLE", "DOCKED")
    assert not _of(effects, GoalEnded), "nobody asked: no action to answer"


def test_a_trigger_that_fires_asks_for_a_tick_at_once_and_a_reading_that_does_not_fire_does_not() -> None:
    ex = _executive()
    ex.battery_reading(0.5, False)
    assert not ex.decision_due, "above the threshold: nothing to start"
    ex.battery_reading(0.2, False)
    assert ex.decision_due, "the trigger fired: the docking should start on this reading's time"
    ex.step(_heard(0.0, battery=0.2))
    assert ex.task is not None and ex.life.kind is TaskKind.DOCK
    assert not ex.decision_due, "the tick started it"
    ex.battery_reading(0.19, False)
    assert not ex.decision_due, "still low, already docking: the trigger does not fire again"


def test_a_goal_that_replaces_another_cancels_it_and_a_foreign_cancel_is_answered_at_once() -> None:
    ex = _executive()
    dock_goal = Goal(object(), TaskKind.DOCK)
    assert ex.handle(DockGoal(dock_goal, DockRequest()), _heard(0.0)) == []
    undock_goal = Goal(object(), TaskKind.UNDOCK)
    effects = ex.handle(UndockGoal(undock_goal, 30.0), _heard(0.1))
    assert _acts(effects) == [GoalEnded(dock_goal, Outcome.CANCELED, DockRobotResult(success=False))]
    assert _said(effects) == ["DockingRun replaced by UndockingRun"]
    assert ex.task is not None and ex.task.state_name() == "UNDOCKING" and ex.life.goal is undock_goal
    stray = Goal(object(), TaskKind.DOCK)
    assert ex.handle(CancelGoal(stray), _heard(0.2)) == [
        GoalEnded(stray, Outcome.CANCELED, DockRobotResult(success=False))
    ]


def test_a_cancelled_goal_ends_canceled_once_the_planner_lets_go_and_the_robot_is_left_stopped() -> None:
    ex = _executive()
    goal = Goal(object(), TaskKind.UNDOCK)
    ex.handle(UndockGoal(goal, 30.0), _heard(0.0))
    effects = ex.handle(CancelGoal(goal), _heard(0.01))
    assert _acts(effects) == [], "the running task is asked to stop"
    assert _said(effects) == ["UndockingRun: cancel requested"]
    effects = ex.step(_heard(0.05))
    assert _of(effects, GoalEnded) == [GoalEnded(goal, Outcome.CANCELED, UndockRobotResult(success=False))]
    assert ex.task is None and _states(effects) == ["HOLDING"], "an action took over: nothing automatic"


def test_docking_feedback_goes_to_the_goal_on_change_and_then_every_period() -> None:
    ex = _executive(feedback_period_s=1.0)
    goal = Goal(object(), TaskKind.DOCK)
    ex.handle(DockGoal(goal, DockRequest()), _heard(0.0))
    first = _of(ex.step(_heard(0.0)), GoalFeedback)
    assert len(first) == 1 and first[0].goal is goal
    navigating = NavHeard(busy=True)  # the goal went out with the first step; the planner works on it
    assert _of(ex.step(_heard(0.05, nav=navigating)), GoalFeedback) == [], "same state within the period"
    assert len(_of(ex.step(_heard(1.1, nav=navigating)), GoalFeedback)) == 1


def test_a_clock_reset_cancels_what_runs() -> None:
    ex = _executive()
    goal = Goal(object(), TaskKind.UNDOCK)
    ex.handle(UndockGoal(goal, 30.0), _heard(5.0))
    effects = ex.step(_heard(0.0, clock_reset=True))
    assert _of(effects, GoalEnded) == [GoalEnded(goal, Outcome.CANCELED, UndockRobotResult(success=False))]


# --- the fleet's dock claim ----------------------------------------------------------------------------


def test_with_a_fleet_it_waits_for_a_dock_asks_with_path_lengths_and_docks_once_granted() -> None:
    ex = _executive(CORRIDOR, "r1", fleet=True, patrol=[(1.2, 3.0, 0.0)])
    goal = Goal(object(), TaskKind.DOCK)
    here = Pose2D(1.2, 3.0, 0.0)
    ex.handle(DockGoal(goal, DockRequest()), _heard(0.0, here))
    assert ex.task is not None and ex.task.state_name() == "WAITING_FOR_DOCK"
    effects = ex.step(_heard(0.05, here, battery=0.5))
    asks = _of(effects, Reserve)
    assert len(asks) == 1 and asks[0].battery == 0.5 and asks[0].dock_id == ""
    lengths = asks[0].path_lengths
    assert lengths and set(lengths) == {d.id for d in ex.database}
    assert all(
        length >= here.distance_to(d.pose2d) - 1e-9 for d in ex.database for length in [lengths[d.id]]
    ), "a path is never shorter than the straight line"
    assert _of(ex.step(_heard(0.1, here, battery=0.5)), Reserve) == [], "one request in flight"
    queued = FleetAnswer(
        False, queue_position=1, reason="both docks taken", holding_pose=Pose2D(2.0, 3.0, 0.0)
    )
    ex.handle(FleetReserved(queued), _heard(0.2, here))
    drives = [e.orders for e in _of(ex.step(_heard(0.25, here, battery=0.5)), Drive)]
    assert any(o.send_goal == Pose2D(2.0, 3.0, 0.0) for o in drives), "it goes to the holding pose"
    dock_id = next(iter(ex.database)).id
    ex.handle(FleetReserved(FleetAnswer(True, dock_id)), _heard(1.3, here))
    effects = ex.step(_heard(1.35, here, battery=0.5))
    assert ex.task is not None and ex.task.dock_request.dock_id == dock_id
    assert ex.life.goal is goal and not _of(effects, GoalEnded), (
        "the same goal carries on into the docking run"
    )


def test_with_the_fleet_down_it_docks_at_a_dock_seen_free_and_releases_after_undocking() -> None:
    ex = _executive(CORRIDOR, "r1", fleet=True, patrol=[(1.2, 3.0, 0.0)], fleet_patience_s=5.0)
    here = Pose2D(1.2, 3.0, 0.0)
    ex.handle(DockGoal(Goal(object(), TaskKind.DOCK), DockRequest()), _heard(0.0, here))
    ex.step(_heard(0.05, here, battery=0.5))
    ex.handle(FleetReserved(None, TimeoutError("no answer")), _heard(1.0, here))
    claimed = _of(
        ex.step(_heard(6.0, here, battery=0.5, scan=LidarReturns.of_points(np.zeros((0, 2))))), Reserve
    )
    assert ex.task is not None and ex.task.state_name() != "WAITING_FOR_DOCK"
    assert ex.claim is not None and ex.claim.granted_dock == ex.task.dock_request.dock_id
    assert len(claimed) == 1 and claimed[0].path_lengths is None, "the dock it took is claimed, not asked for"
    ex.handle(FleetReserved(FleetAnswer(True, ex.claim.dock_id)), _heard(6.01, here))
    # Undocked later: the dock is released, asked until the fleet answers.
    undock = Goal(object(), TaskKind.UNDOCK)
    ex.handle(UndockGoal(undock, 30.0), _heard(7.0, here))
    ex.task.finish(Outcome.SUCCEEDED)
    ex.step(_heard(7.05, here, battery=0.5))
    releases = [e for t in (8.1, 8.2) for e in _of(ex.step(_heard(t, here, battery=0.5)), Release)]
    assert len(releases) == 1
    ex.handle(FleetReleased(""), _heard(8.3, here))
    assert not ex.claim.release_pending


# --- traffic -------------------------------------------------------------------------------------------


def test_met_head_on_in_the_corridor_by_a_robot_with_priority_it_gives_way_then_patrols_on() -> None:
    ex = _executive(CORRIDOR, "r1", fleet=True)
    ex.battery_reading(0.8, False)
    me = Pose2D(3.5, 3.0, 0.0)
    ex.step(_heard(0.0, me, battery=0.8))
    assert ex.task is not None and ex.task.state_name() == "PATROLLING" and ex.task.under_way
    other = Peer("r2", Pose2D(6.0, 3.0, math.pi), 0.4, True)
    effects = ex.step(_heard(0.05, me, battery=0.8, peers=(other,)))
    assert ex.task is not None and ex.task.state_name() == "GIVING_WAY"
    assert _states(effects) == ["GIVING_WAY"]
    ex.step(_heard(2.0, me, battery=0.8, peers=()))  # r2 has gone (not heard from): the way is clear
    effects = ex.step(_heard(2.05, me, battery=0.8))
    assert ex.task is not None and ex.task.state_name() == "PATROLLING", "the mission patrols on"


def test_the_robot_with_priority_waits_for_the_other_to_back_out_and_then_drives_on() -> None:
    ex = _executive(CORRIDOR, "r1", fleet=True)
    ex.battery_reading(0.3, False)
    me = Pose2D(3.5, 3.0, 0.0)
    ex.step(_heard(0.0, me, battery=0.3))
    other = Peer("r2", Pose2D(6.0, 3.0, math.pi), 0.9, True)
    ex.step(_heard(0.05, me, battery=0.3, peers=(other,)))
    assert ex.task is not None and ex.task.state_name() == "GIVING_WAY"
    ex.step(_heard(0.1, me, battery=0.3, peers=(other,)))
    assert "back out" in ex.task.holding
    backed_out = Peer("r2", Pose2D(6.0, 4.2, math.pi / 2), 0.9, False, giving_way=True)
    ex.step(_heard(2.0, me, battery=0.3, peers=(backed_out,)))
    ex.step(_heard(2.05, me, battery=0.3, peers=(backed_out,)))
    assert ex.task is not None and ex.task.state_name() == "PATROLLING"


def test_a_dock_goal_cancelled_while_giving_way_ends_cancelled_and_is_not_resumed() -> None:
    ex = _executive(CORRIDOR, "r1", fleet=True)
    me = Pose2D(3.5, 3.0, 0.0)
    goal = Goal(object(), TaskKind.DOCK)
    ex.handle(DockGoal(goal, DockRequest(dock_pose=Pose2D(9.0, 3.0, 0.0))), _heard(0.0, me))
    ex.step(_heard(0.0, me, battery=0.8))
    ex.task.enter(ex.task.phase.__class__.NAV_TO_STAGING, 0.0)  # on its way to the staging pose
    other = Peer("r2", Pose2D(6.0, 3.0, math.pi), 0.4, True)
    ex.step(_heard(0.05, me, battery=0.8, peers=(other,)))
    assert ex.task is not None and ex.task.state_name() == "GIVING_WAY" and ex.life.goal is goal
    ex.handle(CancelGoal(goal), _heard(0.1, me))
    effects = ex.step(_heard(0.15, me, battery=0.8, peers=(other,)))
    assert _of(effects, GoalEnded) == [GoalEnded(goal, Outcome.CANCELED, DockRobotResult(success=False))]
    assert ex.task is None, "the docking it interrupted is not started again"
