"""Undocking, patrolling, the mission's decisions and the drive arbiter."""

from __future__ import annotations

import pytest

from services.docking.approach import dock_frame_error
from services.docking.dock_db import DockDatabase
from services.docking.drive_arbiter import DriveArbiter, DriveOrders, Hold
from services.docking.errors import DockingErrorCode
from services.docking.mission import Mission, MissionMode, MissionOrder, TaskKind
from services.docking.patrol import Patrol
from services.docking.task_io import STOP, Navigate, NavOutcome, NavStatus, Outcome, TickInputs, Velocity
from services.docking.undocking_run import UndockingRun
from shared.geometry import Pose2D
from shared.world import Dock
from tests.unit.docking.harness import SEED_DOCK, KinematicWorld

DATABASE = DockDatabase([Dock(id="home", pose=SEED_DOCK.as_tuple())])

# --- undocking ----------------------------------------------------------------------------------------


def test_undock_backs_straight_out_to_staging_and_confirms() -> None:
    world = KinematicWorld(SEED_DOCK.compose(Pose2D(-0.01, 0.005, 0.02)))
    assert world.mated
    run = UndockingRun(DATABASE)
    world.run(run, 30.0)
    assert run.result is not None and run.result.success, run.result
    error = dock_frame_error(world.true_pose, SEED_DOCK)
    assert error.along_m == pytest.approx(-0.7, abs=0.06) and abs(error.lateral_m) < 0.02
    assert all(c.linear_x_mps <= 0.0 for _, c in world.log.published)
    assert world.log.published[-1][1].is_zero and not world.log.goals


def test_undock_when_not_docked_succeeds_at_once() -> None:
    world = KinematicWorld(Pose2D(1.0, 3.0, 0.0))
    run = UndockingRun(DATABASE)
    world.run(run, 5.0)
    assert run.result is not None and run.result.success and run.message == "not docked"
    assert not any(c.linear_x_mps for _, c in world.log.published)


def test_undock_holds_for_something_behind_and_gives_up_in_time() -> None:
    world = KinematicWorld(SEED_DOCK)
    world.blocked_behind = lambda _w: True
    run = UndockingRun(DATABASE, max_undocking_time_s=2.0)
    world.run(run, 10.0)
    assert run.result is not None and run.result.error_code is DockingErrorCode.FAILED_TO_CONTROL
    assert all(c.is_zero for _, c in world.log.published)
    assert world.mated


def test_undock_fails_if_charging_does_not_stop() -> None:
    world = KinematicWorld(SEED_DOCK)
    world.charging_override = True
    run = UndockingRun(DATABASE)
    world.run(run, 30.0)
    assert run.result is not None and run.result.outcome is Outcome.FAILED
    assert run.result.error_code is DockingErrorCode.FAILED_TO_CONTROL and "still charging" in run.message


# --- patrol -------------------------------------------------------------------------------------------

WAYPOINTS = [Pose2D(0.5, 3.5, 0.0), Pose2D(1.0, 2.0, -1.57), Pose2D(-1.5, 3.0, 3.0)]


def test_patrol_visits_the_waypoints_in_a_loop() -> None:
    world = KinematicWorld(Pose2D(0.0, 3.0, 0.0), nav_duration_s=1.0)
    patrol = Patrol(WAYPOINTS, start_index=1)
    world.run(patrol, 8.0)
    goals = [g for _, g in world.log.goals]
    assert goals[:5] == [WAYPOINTS[1], WAYPOINTS[2], WAYPOINTS[0], WAYPOINTS[1], WAYPOINTS[2]]
    assert patrol.laps >= 1 and not patrol.done


def test_patrol_moves_on_after_a_failure_and_stops_when_cancelled() -> None:
    world = KinematicWorld(Pose2D(0.0, 3.0, 0.0), nav_duration_s=0.5, nav_fails=1)
    patrol = Patrol(WAYPOINTS, retry_delay_s=2.0)
    world.run(patrol, 1.0)
    assert [g for _, g in world.log.goals] == [WAYPOINTS[0]] and not world.nav_busy
    world.run(patrol, 5.0, until=lambda: len(world.log.goals) == 2)
    failed_at_s, (next_sent_s, next_goal) = 0.5, world.log.goals[-1]
    assert next_goal == WAYPOINTS[1] and 2.0 <= next_sent_s - failed_at_s <= 2.15
    assert world.nav_busy
    patrol.cancel()
    world.run(patrol, 2.0)
    assert patrol.result is not None and patrol.result.outcome is Outcome.CANCELED
    assert world.log.cancels and world.log.overlaps == 0


def test_patrol_needs_waypoints() -> None:
    with pytest.raises(ValueError):
        Patrol([])


# --- mission ------------------------------------------------------------------------------------------


def test_mission_docks_on_a_crossing_or_a_first_low_reading() -> None:
    mission = Mission()
    assert not mission.battery(0.30, False)
    assert mission.decide(0.0, None) is None
    assert mission.battery(0.249, False)
    assert mission.decide(0.1, None) is MissionOrder.DOCK
    assert mission.decide(0.2, None) is None  # once
    restarted = Mission()
    assert restarted.battery(0.2, False)
    assert restarted.decide(0.0, None) is MissionOrder.DOCK


def test_auto_dock_switched_while_running() -> None:
    """``zendock param set docking auto_dock false``: a user's program docks, the mission does not react
    to the same low battery; switched on again while low, the mission docks."""
    mission = Mission()
    mission.battery(0.30, False)
    mission.set_auto_dock(False)
    assert mission.battery(0.2, False)  # the trigger still fires ...
    assert mission.decide(0.0, None) is None  # ... and starts nothing
    mission.set_auto_dock(True)
    assert mission.decide(0.1, None) is MissionOrder.DOCK
    wanted = Mission()
    wanted.battery(0.2, False)
    wanted.set_auto_dock(False)  # a docking wanted and not yet started is dropped
    assert wanted.decide(0.0, None) is None
    charging = Mission()
    charging.battery(0.2, True)
    charging.set_auto_dock(False)
    charging.set_auto_dock(True)  # low but charging: nothing to do
    assert charging.decide(0.0, None) is None


def test_mission_leaves_an_action_alone() -> None:
    mission = Mission()
    mission.battery(0.2, False)
    assert mission.decide(0.0, TaskKind.UNDOCK) is None
    assert mission.decide(0.1, None) is None  # the wish was dropped, not kept for later


def test_mission_patrols_docks_and_resumes() -> None:
    mission = Mission(WAYPOINTS, resume_at=0.8)
    mission.battery(0.6, False)
    assert mission.decide(0.0, None) is MissionOrder.PATROL
    mission.battery(0.24, False)
    assert mission.decide(1.0, TaskKind.PATROL) is MissionOrder.DOCK
    mission.finished(TaskKind.DOCK, True, False, 2.0)
    assert mission.mode is MissionMode.CHARGING
    mission.battery(0.5, True)
    assert mission.decide(3.0, None) is None
    mission.battery(0.81, True)
    assert mission.decide(4.0, None) is MissionOrder.UNDOCK
    mission.finished(TaskKind.UNDOCK, True, False, 5.0)
    mission.battery(0.8, False)
    assert mission.decide(6.0, None) is MissionOrder.PATROL


def test_mission_without_patrol_stays_docked() -> None:
    mission = Mission(resume_at=0.8)
    mission.battery(0.2, False)
    assert mission.decide(0.0, None) is MissionOrder.DOCK
    mission.finished(TaskKind.DOCK, True, False, 1.0)
    mission.battery(1.0, True)
    assert mission.decide(2.0, None) is None


def test_an_explicit_dock_is_not_undone_at_resume_at() -> None:
    mission = Mission(WAYPOINTS, resume_at=0.8)
    mission.battery(0.9, False)
    mission.finished(TaskKind.DOCK, True, True, 1.0)
    mission.battery(0.95, True)
    assert mission.mode is MissionMode.HOLDING and mission.decide(2.0, None) is None
    mission.finished(TaskKind.UNDOCK, True, True, 3.0)
    mission.battery(0.95, False)
    assert mission.decide(4.0, None) is MissionOrder.PATROL


def test_a_failed_mission_dock_is_tried_again_later_while_low() -> None:
    mission = Mission(redock_delay_s=30.0)
    mission.battery(0.2, False)
    assert mission.decide(0.0, None) is MissionOrder.DOCK
    mission.finished(TaskKind.DOCK, False, False, 10.0)
    mission.battery(0.19, False)
    assert mission.decide(20.0, None) is None
    assert mission.decide(40.0, None) is MissionOrder.DOCK


def test_started_on_the_dock_it_undocks_once_charged() -> None:
    mission = Mission(WAYPOINTS, resume_at=0.8)
    mission.battery(0.5, True)
    assert mission.decide(0.0, None) is None
    mission.battery(0.85, True)
    assert mission.decide(1.0, None) is MissionOrder.UNDOCK


def test_resume_at_must_be_above_the_threshold() -> None:
    with pytest.raises(ValueError):
        Mission(resume_at=0.2, low_threshold=0.25)


# --- the arbiter --------------------------------------------------------------------------------------


def test_no_command_while_the_planner_drives() -> None:
    arbiter = DriveArbiter(cancel_retry_s=1.0)
    assert arbiter.navigate(Navigate(Pose2D(1.0, 2.0, 0.0), "a")) == DriveOrders(
        send_goal=Pose2D(1.0, 2.0, 0.0), hold=Hold.UNTIL_DRIVEN
    )
    assert (
        arbiter.navigate(Navigate(Pose2D(1.0, 2.0, 0.0), "a")) == DriveOrders()
    )  # same request: sent already
    assert arbiter.velocity(Velocity(0.1, 0.0), nav_busy=True, now_s=0.0) == DriveOrders(
        cancel_nav=True, hold=Hold.UNTIL_LET_GO
    )
    assert arbiter.velocity(Velocity(0.1, 0.0), nav_busy=True, now_s=0.5) == DriveOrders()
    assert arbiter.velocity(Velocity(0.1, 0.0), nav_busy=True, now_s=1.1) == DriveOrders(cancel_nav=True)
    assert arbiter.velocity(Velocity(0.1, 0.0), nav_busy=False, now_s=1.2) == DriveOrders(
        publish=Velocity(0.1, 0.0), hold=Hold.LET_GO
    )
    assert arbiter.velocity(Velocity(0.1, 0.0), nav_busy=False, now_s=1.25) == DriveOrders(
        publish=Velocity(0.1, 0.0)
    )  # let go once


def test_each_handoff_holds_the_world_until_the_service_drives_or_leaves_off() -> None:
    """A goal sent, or a goal cancelled to drive: the robot stands between two drivers, and the world
    is held from that tick (see the module docstring); the service lets go when it publishes or ends."""
    arbiter = DriveArbiter()
    assert arbiter.navigate(Navigate(Pose2D(), "a")).hold is Hold.UNTIL_DRIVEN
    assert arbiter.release() == DriveOrders(hold=Hold.LET_GO)  # the task ended: nobody drives
    assert arbiter.release() == DriveOrders()
    arbiter.velocity(Velocity(0.2, 0.0), nav_busy=False, now_s=0.0)
    orders = arbiter.navigate(Navigate(Pose2D(), "b"))
    assert (orders.publish, orders.hold) == (STOP, Hold.UNTIL_DRIVEN)
    assert arbiter.release() == DriveOrders(hold=Hold.LET_GO)


def test_one_zero_command_before_the_planner_takes_over() -> None:
    arbiter = DriveArbiter()
    arbiter.velocity(Velocity(0.2, 0.3), nav_busy=False, now_s=0.0)
    orders = arbiter.navigate(Navigate(Pose2D(), "b"))
    assert orders.publish == STOP and orders.send_goal == Pose2D()
    assert arbiter.release() == DriveOrders(hold=Hold.LET_GO)  # stopped already; the goal's hold let go
    arbiter.velocity(STOP, nav_busy=False, now_s=1.0)
    assert arbiter.navigate(Navigate(Pose2D(), "c")).publish is None  # the last command was a zero


def test_release_leaves_the_robot_stopped() -> None:
    arbiter = DriveArbiter()
    arbiter.velocity(Velocity(-0.1, 0.0), nav_busy=False, now_s=0.0)
    assert arbiter.release() == DriveOrders(publish=STOP)
    assert arbiter.release() == DriveOrders()


def test_nav_status_reports_only_its_own_request() -> None:
    status = NavStatus(key="a", busy=False, outcome=NavOutcome.SUCCEEDED)
    assert status.finished("a") is NavOutcome.SUCCEEDED
    assert status.finished("b") is None
    assert NavStatus(key="a", busy=True).finished("a") is None
    assert NavStatus(key="a", busy=False, outcome=None).finished("a") is NavOutcome.FAILED


def test_tasks_are_stepped_once_done_do_nothing() -> None:
    run = UndockingRun(DATABASE)
    run.cancel()
    assert run.step(TickInputs(now_s=0.0)) == STOP
    assert run.result is not None and run.result.outcome is Outcome.CANCELED
    assert run.step(TickInputs(now_s=0.1)) is None
