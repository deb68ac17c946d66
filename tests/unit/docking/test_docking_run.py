"""The docking run's state machine, stepped in the kinematic world of :mod:`tests.unit.docking.harness`."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from services.docking.approach import dock_frame_error, graceful_staging_pose, line_approach, offset_along
from services.docking.approach_control import MISALIGNED, GracefulApproach, SeedApproach
from services.docking.dock_db import DockDatabase
from services.docking.docking_run import DockingConfig, DockingRun, DockRequest, RunPhase, facing_dock_closely
from services.docking.errors import DockingErrorCode, DockingState
from services.docking.kinematics import DiffDriveModel
from services.docking.task_io import Outcome, TickInputs
from shared.geometry import Pose2D
from shared.world import Dock
from tests.unit.docking.harness import SEED_DOCK, KinematicWorld

FAR = Pose2D(1.8, 4.2, math.pi)
DATABASE = DockDatabase(
    [Dock(id="home", pose=SEED_DOCK.as_tuple()), Dock(id="spare", pose=(2.0, 0.83, -math.pi / 2))]
)


def graceful_run(request: DockRequest | None = None, **config: object) -> DockingRun:
    return DockingRun(
        request or DockRequest(dock_id="home"), DATABASE, GracefulApproach(), DockingConfig(**config)
    )  # type: ignore[arg-type]


def run_with_states(world: KinematicWorld, run: DockingRun, max_time_s: float) -> list[DockingState]:
    states: list[DockingState] = []
    while world.now_s < max_time_s and not run.done:
        world.tick(run)
        if not states or states[-1] != run.feedback_state:
            states.append(run.feedback_state)
    return states


def test_graceful_run_stages_perceives_approaches_and_docks() -> None:
    world = KinematicWorld(FAR)
    run = graceful_run()
    states = run_with_states(world, run, 60.0)
    assert run.result is not None and run.result.outcome is Outcome.SUCCEEDED, run.result
    assert states == [
        DockingState.NAV_TO_STAGING_POSE,
        DockingState.INITIAL_PERCEPTION,
        DockingState.CONTROLLING,
    ]
    assert [g for _, g in world.log.goals] == [graceful_staging_pose(SEED_DOCK)]
    assert world.mated and run.num_retries == 0 and not run.blind
    assert world.log.overlaps == 0
    assert world.log.published[-1][1].is_zero


def test_nearest_dock_by_default_and_a_given_pose() -> None:
    world = KinematicWorld(Pose2D(1.5, 2.0, 0.0), dock=Pose2D(2.0, 0.83, -math.pi / 2))
    run = graceful_run(DockRequest())
    world.run(run, 60.0)
    assert run.dock_id == "spare" and run.result is not None and run.result.success
    world = KinematicWorld(FAR)
    run = graceful_run(DockRequest(dock_pose=SEED_DOCK))
    world.run(run, 60.0)
    assert run.dock_id == "" and run.result is not None and run.result.success


@pytest.mark.parametrize("detections", [True, False])
def test_detections_cancel_a_localisation_error_that_blind_docking_cannot(detections: bool) -> None:
    world = KinematicWorld(FAR, error=Pose2D(0.03, 0.06, 0.03), detections=detections)
    run = graceful_run(max_retries=1, wait_charge_timeout_s=2.0)
    world.run(run, 120.0)
    assert run.result is not None
    if detections:
        assert run.result.success and world.mated and not run.blind
        assert abs(dock_frame_error(world.true_pose, SEED_DOCK).lateral_m) < 0.01
    else:
        assert run.blind and not world.mated
        assert (
            run.result.outcome is Outcome.FAILED
            and run.result.error_code is DockingErrorCode.FAILED_TO_CHARGE
        )
        assert run.result.num_retries == 1
    assert world.log.overlaps == 0


def test_seed_run_uses_the_line_approach_at_its_own_rate() -> None:
    world = KinematicWorld(FAR, period_s=0.1)
    run = DockingRun(
        DockRequest(dock_id="home"), DATABASE, SeedApproach(), DockingConfig(wait_for_detection=False)
    )
    world.run(run, 200.0)
    assert run.result is not None and run.result.success, run.result
    assert [g for _, g in world.log.goals] == [line_approach(SEED_DOCK).staging_goal]
    commands = {(c.linear_x_mps, c.angular_z_radps) for _, c in world.log.published}
    assert commands <= {(0.0, 0.0), (0.08, 0.0), (0.0, 0.1), (0.0, -0.1)}
    assert world.mated


def test_failed_staging_is_retried_and_counted() -> None:
    world = KinematicWorld(FAR, nav_fails=1)
    run = graceful_run()
    states = run_with_states(world, run, 60.0)
    assert run.result is not None and run.result.success and run.result.num_retries == 1
    assert DockingState.RETRY in states and len(world.log.goals) == 2


def test_retries_run_out_with_the_last_error() -> None:
    world = KinematicWorld(FAR, nav_fails=10)
    run = graceful_run(max_retries=2)
    world.run(run, 60.0)
    assert run.result is not None and run.result.outcome is Outcome.FAILED
    assert (run.result.error_code, run.result.num_retries, len(world.log.goals)) == (
        DockingErrorCode.FAILED_TO_STAGE,
        2,
        3,
    )


def test_unknown_dock_fails_at_once_without_moving() -> None:
    world = KinematicWorld(FAR)
    run = graceful_run(DockRequest(dock_id="garage"))
    world.run(run, 5.0)
    assert run.result is not None and run.result.error_code is DockingErrorCode.DOCK_NOT_IN_DB
    assert run.result.num_retries == 0 and not world.log.goals
    assert all(c.is_zero for _, c in world.log.published)


def test_already_charging_succeeds_at_once() -> None:
    world = KinematicWorld(SEED_DOCK)
    run = graceful_run()
    world.run(run, 5.0)
    assert run.result is not None and run.result.success and run.message == "already charging"
    assert not world.log.goals


def test_a_robot_in_front_of_the_dock_backs_off_before_staging() -> None:
    start = SEED_DOCK.compose(Pose2D(-0.2, 0.01, 0.05))  # stopped mid-approach, not mated
    assert facing_dock_closely(start, SEED_DOCK, 0.35)
    world = KinematicWorld(start, charger_works=True)
    run = graceful_run()
    world.tick(run)
    world.tick(run)
    assert run.phase is RunPhase.RETREAT
    world.run(run, 60.0)
    assert run.result is not None and run.result.success
    first_goal_s = world.log.goals[0][0]
    backing = [c for t, c in world.log.published if t < first_goal_s]
    assert any(c.linear_x_mps < 0.0 for c in backing)
    assert world.log.overlaps == 0


def test_without_the_planner_a_retry_backs_off_to_staging() -> None:
    staging = graceful_staging_pose(SEED_DOCK)
    world = KinematicWorld(staging, charger_works=False)
    run = graceful_run(
        DockRequest(dock_id="home", navigate_to_staging_pose=False), max_retries=1, wait_charge_timeout_s=1.0
    )
    world.run(run, 60.0)
    assert not world.log.goals
    assert run.result is not None and run.result.error_code is DockingErrorCode.FAILED_TO_CHARGE
    assert run.result.num_retries == 1
    assert any(c.linear_x_mps < 0.0 for _, c in world.log.published)


def test_cancel_while_controlling_publishes_zero() -> None:
    world = KinematicWorld(FAR)
    run = graceful_run()
    world.run(run, 60.0, until=lambda: run.phase is RunPhase.CONTROLLING and world.robot.v_mps > 0.1)
    run.cancel()
    world.run(run, 5.0)
    assert run.result is not None and run.result.outcome is Outcome.CANCELED
    assert world.log.published[-1][1].is_zero and not world.mated


def test_cancel_while_staging_cancels_the_planner_first() -> None:
    world = KinematicWorld(FAR, nav_duration_s=10.0)
    run = graceful_run()
    world.run(run, 60.0, until=lambda: world.nav_busy)
    run.cancel()
    world.run(run, 5.0)
    assert run.result is not None and run.result.outcome is Outcome.CANCELED
    assert world.log.cancels and world.log.overlaps == 0
    assert world.log.published[-1][1].is_zero


def test_an_obstacle_holds_the_robot_until_it_goes() -> None:
    world = KinematicWorld(FAR)
    run = graceful_run()
    window: list[float] = []

    def blocked(w: KinematicWorld) -> bool:
        if run.phase is RunPhase.CONTROLLING and not window:
            window.append(w.now_s)
        return bool(window) and w.now_s < window[0] + 2.0

    world.blocked_ahead = blocked
    world.run(run, 60.0)
    assert run.result is not None and run.result.success
    held = [c for t, c in world.log.published if window[0] <= t < window[0] + 2.0]
    assert held and all(c.linear_x_mps <= 0.0 for c in held)


def test_an_obstacle_that_stays_fails_the_attempt() -> None:
    world = KinematicWorld(FAR)
    run = graceful_run(max_retries=0, obstacle_timeout_s=3.0)
    world.blocked_ahead = lambda _w: True
    world.run(run, 60.0)
    assert run.result is not None and run.result.error_code is DockingErrorCode.FAILED_TO_CONTROL
    assert all(c.linear_x_mps <= 0.0 for _, c in world.log.published)


def test_stale_localisation_holds_then_resumes() -> None:
    world = KinematicWorld(FAR)
    run = graceful_run()
    gap: list[float] = []

    def available(w: KinematicWorld) -> bool:
        if run.phase is RunPhase.CONTROLLING and not gap and w.robot.v_mps > 0.1:
            gap.append(w.now_s)
        return not gap or w.now_s >= gap[0] + 1.0

    world.pose_available = available
    world.run(run, 60.0)
    assert run.result is not None and run.result.success
    during = [c for t, c in world.log.published if gap[0] <= t < gap[0] + 1.0]
    assert during and all(c.is_zero for c in during)


def test_no_charge_means_wait_then_fail_to_charge() -> None:
    world = KinematicWorld(FAR, charger_works=False)
    run = graceful_run(max_retries=0, wait_charge_timeout_s=2.0)
    states = run_with_states(world, run, 60.0)
    assert DockingState.WAIT_FOR_CHARGE in states
    assert run.result is not None and run.result.error_code is DockingErrorCode.FAILED_TO_CHARGE


def test_the_whole_run_is_bounded() -> None:
    world = KinematicWorld(FAR, nav_duration_s=100.0)
    run = graceful_run(max_docking_time_s=5.0)
    world.run(run, 30.0)
    assert run.result is not None and run.result.error_code is DockingErrorCode.TIMEOUT
    assert world.log.cancels  # the planner's goal was dropped before the final stop


def test_nearest_dock_waits_for_a_pose_then_times_out() -> None:
    run = graceful_run(DockRequest(), start_timeout_s=1.0)
    now, intents = 0.0, []
    while not run.done and now < 5.0:
        intents.append(run.step(TickInputs(now_s=now)))
        now += 0.05
    assert run.result is not None and run.result.error_code is DockingErrorCode.TIMEOUT
    assert 0.95 < now < 1.2 and all(i is None for i in intents[:-1])  # nothing to drive without a pose


def handover_run(approach: GracefulApproach | None = None, **config: object) -> DockingRun:
    settings: dict[str, object] = {
        "continuous_perception": True,
        "handover_distance_m": 0.45,
        "max_control_pose_age_s": 0.25,
    } | config
    return DockingRun(
        DockRequest(dock_id="home"), DATABASE, approach or GracefulApproach(), DockingConfig(**settings)
    )  # type: ignore[arg-type]


def test_the_approach_takes_over_from_navigation_near_the_staging_pose() -> None:
    """Close to the staging pose and facing the dock, the run cancels navigation rather than wait for it
    to stop there, drives nothing until the planner has let go, and docks from where the robot is."""
    world = KinematicWorld(
        offset_along(SEED_DOCK, -1.6), nav_duration_s=30.0, error=Pose2D(0.03, -0.02, 0.02)
    )
    run = handover_run()
    states = run_with_states(world, run, 0.5)
    assert run.phase is RunPhase.NAV_TO_STAGING and len(world.log.goals) == 1
    # The planner has brought the robot 0.3 m short of the staging pose, a little askew, still driving.
    world.robot = DiffDriveModel(offset_along(SEED_DOCK, -1.0, 0.05, 0.2), world.robot.limits)
    world.robot.v_mps = 0.4
    states += run_with_states(world, run, 20.0)
    assert run.result is not None and run.result.success, run.result
    assert [s for i, s in enumerate(states) if i == 0 or s != states[i - 1]] == [
        DockingState.NAV_TO_STAGING_POSE,
        DockingState.INITIAL_PERCEPTION,
        DockingState.CONTROLLING,
    ]
    assert len(world.log.goals) == 1 and world.log.cancels and world.log.overlaps == 0
    assert world.now_s < 6.0 and world.mated
    error = dock_frame_error(world.true_pose, SEED_DOCK)
    assert abs(error.lateral_m) < 0.01 and abs(error.yaw_rad) < math.radians(1.0)
    # Already in the zone when the attempt begins: the planner is not even asked.
    world = KinematicWorld(offset_along(SEED_DOCK, -1.0, 0.05, 0.2), nav_duration_s=30.0)
    run = handover_run()
    world.run(run, 20.0)
    assert run.result is not None and run.result.success and not world.log.goals


def test_a_robot_coming_side_on_is_taken_over_while_it_can_still_curve_in() -> None:
    """1.45 rad off the dock's heading, 0.4 m from the staging pose, the dock 0.92 rad to one side: the
    approach's first curve is gentle enough, so it takes over at speed instead of letting navigation stop
    there to turn on the spot."""
    side_on = offset_along(SEED_DOCK, -0.69, 0.40, -1.45)
    assert GracefulApproach().curves_in_from(side_on, SEED_DOCK)
    world = KinematicWorld(offset_along(SEED_DOCK, -1.6), nav_duration_s=30.0)
    run = handover_run()
    states = run_with_states(world, run, 0.5)
    world.robot = DiffDriveModel(side_on, world.robot.limits)
    world.robot.v_mps = 0.4
    states += run_with_states(world, run, 20.0)
    assert run.result is not None and run.result.success, run.result
    assert DockingState.CONTROLLING in states and world.log.cancels and world.log.overlaps == 0
    assert world.now_s < 5.0 and world.mated
    assert abs(dock_frame_error(world.true_pose, SEED_DOCK).lateral_m) < 0.01


@pytest.mark.parametrize("allow_blind", [True, False])
def test_a_takeover_with_no_dock_in_view_goes_blind_as_the_staging_pose_would(
    allow_blind: bool, caplog: pytest.LogCaptureFixture
) -> None:
    """Handed over at once (the robot starts at the staging pose) and no detection ever comes: the approach
    gives them the perception timeout, then docks on the database pose saying so, or fails with 904."""
    # Without the permission, a localisation error keeps the robot off the plate: it arrives uncharged.
    error = Pose2D(0.0, 0.0, 0.0) if allow_blind else Pose2D(0.03, 0.06, 0.03)
    world = KinematicWorld(graceful_staging_pose(SEED_DOCK), detections=False, error=error)
    run = handover_run(allow_blind_docking=allow_blind, max_retries=0)
    with caplog.at_level("WARNING", logger="services.docking.docking_run"):
        world.run(run, 60.0)
    assert run.result is not None and not world.log.goals  # no navigation: the approach took over at once
    if allow_blind:
        assert run.result.success and world.mated and run.blind
        assert "docking on the database pose" in caplog.text
    else:
        assert run.result.error_code is DockingErrorCode.FAILED_TO_DETECT_DOCK and not run.blind
        assert "taking over from navigation" in run.result.message


def test_a_takeover_that_sees_the_dock_is_not_blind() -> None:
    world = KinematicWorld(graceful_staging_pose(SEED_DOCK))
    run = handover_run(max_retries=0)
    world.run(run, 60.0)
    assert run.result is not None and run.result.success and not run.blind and not world.log.goals


def test_no_takeover_far_from_staging_or_facing_away() -> None:
    # Far; facing away; and within the yaw and bearing limits but so close to the axis, heading off it,
    # that the approach would have to stop and turn on the spot first (its curve 9.5 /m).
    sharp = offset_along(SEED_DOCK, -1.0, -0.2, -0.8)
    assert not GracefulApproach().curves_in_from(sharp, SEED_DOCK)
    for start in (offset_along(SEED_DOCK, -1.5), offset_along(SEED_DOCK, -1.0, 0.0, 1.3), sharp):
        world = KinematicWorld(start, nav_duration_s=1.0)
        run = handover_run()
        run_with_states(world, run, 0.5)
        assert run.phase is RunPhase.NAV_TO_STAGING and not world.log.cancels, start
    at_staging = KinematicWorld(offset_along(SEED_DOCK, -0.7, 0.0, math.pi), nav_duration_s=5.0)
    run = handover_run()  # right at the staging pose any heading will do: the approach turns on the spot
    run_with_states(at_staging, run, 0.5)
    assert run.phase is RunPhase.CONTROLLING


class _SkewedOnce(GracefulApproach):
    """Reports the first approach as off its axis at the plate (as a late control tick can make it)."""

    def __init__(self) -> None:
        super().__init__()
        self.misaligned = 0

    def command(self, now_s, pose, pose_age_s, base_twist):  # type: ignore[no-untyped-def]
        if not self.misaligned and dock_frame_error(pose, self._controller.dock_pose).along_m > -0.1:  # type: ignore[union-attr]
            self.misaligned += 1
            return MISALIGNED
        return super().command(now_s, pose, pose_age_s, base_twist)


def test_coming_up_askew_backs_off_and_approaches_again_without_the_planner() -> None:
    world = KinematicWorld(FAR)
    approach = _SkewedOnce()
    run = handover_run(approach)
    states = run_with_states(world, run, 60.0)
    assert run.result is not None and run.result.success and run.result.num_retries == 1, run.result
    assert approach.misaligned == 1 and DockingState.RETRY in states
    assert len(world.log.goals) == 1  # backed off along the dock's axis, not sent round by the planner
    assert world.mated and world.log.overlaps == 0


def test_a_pose_too_old_to_steer_by_holds_the_approach() -> None:
    world = KinematicWorld(FAR)
    run = handover_run()
    late: list[float] = []
    inputs = world.inputs

    def with_late_pose() -> TickInputs:
        fresh = inputs()
        if run.phase is RunPhase.CONTROLLING and not late and world.robot.v_mps > 0.1:
            late.append(world.now_s)
        if late and late[0] <= world.now_s < late[0] + 0.5:
            return replace(fresh, pose_age_s=0.4)
        return fresh

    world.inputs = with_late_pose  # type: ignore[method-assign]
    world.run(run, 60.0)
    assert run.result is not None and run.result.success
    during = [c for t, c in world.log.published if late[0] <= t < late[0] + 0.5]
    assert during and all(c.is_zero for c in during)


def test_on_the_way_no_detections_are_wanted_even_with_the_dock_in_view() -> None:
    run = graceful_run()
    run.step(TickInputs(now_s=0.0, robot_pose=FAR))
    assert run.phase is RunPhase.NAV_TO_STAGING
    assert not run.wants_detections(FAR)
    assert not run.wants_detections(SEED_DOCK.compose(Pose2D(-1.5, 0.2, 0.0))), (
        "the marker in view, on the way"
    )
    run.enter(RunPhase.RETRY, 1.0)
    assert not run.wants_detections(SEED_DOCK.compose(Pose2D(-1.5, 0.2, 0.0)))


def test_from_staging_on_detections_are_wanted_while_the_marker_could_be_in_view() -> None:
    run = graceful_run()
    run.step(TickInputs(now_s=0.0, robot_pose=FAR))
    run.enter(RunPhase.INITIAL_PERCEPTION, 1.0)
    near_facing = SEED_DOCK.compose(Pose2D(-1.5, 0.2, 0.0))
    assert run.wants_detections(near_facing)
    assert not run.wants_detections(SEED_DOCK.compose(Pose2D(-1.5, 0.0, math.radians(32.0)))), (
        "the marker 32 degrees off the heading: at the edge of the view, where it is not found whole"
    )
    assert not run.wants_detections(near_facing.compose(Pose2D(0.0, 0.0, math.pi)))  # turned away
    assert not run.wants_detections(SEED_DOCK.compose(Pose2D(-4.0, 0.0, 0.0)))  # out of range
    assert not run.wants_detections(
        SEED_DOCK.compose(Pose2D(1.5, 0.0, math.pi))
    )  # behind the dock, facing it
    assert not run.wants_detections(SEED_DOCK.compose(Pose2D(-0.2, 1.5, -math.pi / 2)))  # edge-on, 82 deg off
    assert not graceful_run(use_detection=False).wants_detections(near_facing)
    run.enter(RunPhase.CONTROLLING, 2.0)
    assert run.wants_detections(SEED_DOCK.compose(Pose2D(-0.5, 0.3, -0.3)))  # off the axis, facing the marker
    assert not run.wants_detections(SEED_DOCK.compose(Pose2D(-0.5, 0.3, 0.5))), "still turning onto the dock"
    assert not run.wants_detections(SEED_DOCK.compose(Pose2D(-0.7, 0.0, math.pi / 2))), (
        "turned side-on at staging"
    )
    assert run.wants_detections(None)  # no pose yet: look
    assert not run.wants_detections(SEED_DOCK.compose(Pose2D(-0.08, 0.0, 0.0)))  # the marker fills the view
    run.enter(RunPhase.WAIT_FOR_CHARGE, 3.0)
    assert not run.wants_detections(SEED_DOCK.compose(Pose2D(-0.3, 0.0, 0.0)))
