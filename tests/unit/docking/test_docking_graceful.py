import math
from dataclasses import replace

import numpy as np
import pytest

from services.docking.approach import dock_frame_error, offset_along
from services.docking.graceful import (
    NAV2_DOCKING_DEFAULTS,
    NAV2_DOCKING_PARAMS,
    ZENDOCK_PARAMS,
    ZENDOCK_TUNED,
    EgoPolar,
    GracefulDockController,
    GracefulGains,
    VelocityCommand,
    curvature,
    ego_polar,
    smooth_control_law,
    speed_to_brake_in_time,
)
from services.docking.kinematics import PoseSensing, simulate_approach
from shared.geometry import Pose2D

DOCK = Pose2D(-1.0, 0.83, -math.pi / 2)


def test_nav2_default_gains() -> None:
    g = NAV2_DOCKING_DEFAULTS
    assert (g.k_phi, g.k_delta, g.beta, g.lambda_) == (3.0, 2.0, 0.4, 2.0)
    assert (g.v_linear_min_mps, g.v_linear_max_mps, g.v_angular_max_radps, g.slowdown_radius_m) == (
        0.1,
        0.25,
        0.75,
        0.25,
    )


def test_tuned_gains_respect_the_robot_limits() -> None:
    assert ZENDOCK_TUNED.v_linear_max_mps <= 0.5
    assert ZENDOCK_TUNED.v_angular_max_radps <= 1.5


def test_ego_polar_coordinates() -> None:
    ahead = ego_polar(Pose2D(2.0, 0.0, 0.0), Pose2D(0.0, 0.0, 0.0))
    assert (ahead.r_m, ahead.phi_rad, ahead.delta_rad) == pytest.approx((2.0, 0.0, 0.0))
    # Target to the left, facing +y: the line of sight is +90 degrees, so the robot's heading is -90 from it.
    left = ego_polar(Pose2D(0.0, 1.0, math.pi / 2), Pose2D(0.0, 0.0, 0.0))
    assert (left.r_m, left.phi_rad, left.delta_rad) == pytest.approx((1.0, 0.0, -math.pi / 2))


def test_curvature_matches_the_published_law() -> None:
    # Worked by hand: k_delta*(delta - atan(-k_phi*phi)) = 2*(-0.1 + atan(0.6)) = 0.880839,
    # (1 + 3/(1 + 0.36)) * sin(-0.1) = -0.320054, kappa = -(0.880839 - 0.320054) / 1.0 = -0.560785.
    assert curvature(EgoPolar(1.0, 0.2, -0.1), NAV2_DOCKING_DEFAULTS) == pytest.approx(-0.560785, abs=1e-6)
    assert curvature(EgoPolar(0.5, 0.2, -0.1), NAV2_DOCKING_DEFAULTS) == pytest.approx(-1.121570, abs=1e-6)


def test_turns_towards_a_target_on_the_left() -> None:
    v, w = smooth_control_law(Pose2D(0.0, 1.0, math.pi / 2), Pose2D(), NAV2_DOCKING_DEFAULTS).as_tuple()
    assert v > 0.0 and w > 0.0


def test_speed_limits_and_slowdown() -> None:
    g = NAV2_DOCKING_DEFAULTS
    far = smooth_control_law(Pose2D(3.0, 0.0, 0.0), Pose2D(), g)
    assert far.linear_x_mps == pytest.approx(g.v_linear_max_mps) and far.angular_z_radps == 0.0
    near = smooth_control_law(Pose2D(0.05, 0.0, 0.0), Pose2D(), g)
    assert near.linear_x_mps == pytest.approx(g.v_linear_min_mps)  # slowdown floored at v_min
    sharp = smooth_control_law(Pose2D(0.0, 0.1, math.pi), Pose2D(), g)
    assert abs(sharp.angular_z_radps) == pytest.approx(g.v_angular_max_radps)
    # w saturated: v is recomputed from the clamped w, so the robot keeps to the curve (below v_min).
    assert sharp.linear_x_mps == pytest.approx(sharp.angular_z_radps / sharp.curvature_per_m)
    assert sharp.linear_x_mps < g.v_linear_min_mps


def test_backward_motion_drives_in_reverse() -> None:
    v, w = smooth_control_law(
        Pose2D(-1.0, 0.0, 0.0), Pose2D(), NAV2_DOCKING_DEFAULTS, backward=True
    ).as_tuple()
    assert v < 0.0 and w == pytest.approx(0.0)


def test_no_nan_at_or_near_the_target() -> None:
    for gains in (NAV2_DOCKING_DEFAULTS, ZENDOCK_TUNED):
        assert smooth_control_law(Pose2D(1.0, 2.0, 0.3), Pose2D(1.0, 2.0, -2.0), gains).as_tuple() == (
            0.0,
            0.0,
        )
        for r in (1e-12, 1e-7, 1e-5, 1e-3):
            for phi in np.linspace(-math.pi, math.pi, 7):
                target = Pose2D(r, 0.0, float(phi))
                v, w = smooth_control_law(target, Pose2D(), gains).as_tuple()
                assert math.isfinite(v) and math.isfinite(w)
                assert abs(w) <= gains.v_angular_max_radps + 1e-12


def test_gains_are_validated() -> None:
    with pytest.raises(ValueError):
        replace(NAV2_DOCKING_DEFAULTS, k_phi=0.0)
    with pytest.raises(ValueError):
        replace(NAV2_DOCKING_DEFAULTS, v_linear_min_mps=0.5)
    assert isinstance(ZENDOCK_TUNED, GracefulGains)


@pytest.mark.parametrize("params", [ZENDOCK_PARAMS, NAV2_DOCKING_PARAMS], ids=["zendock", "nav2"])
def test_converges_onto_the_dock_from_random_staging_starts(params) -> None:
    rng = np.random.default_rng(7)
    for i in range(15):
        dock = Pose2D(
            float(rng.uniform(-3, 3)), float(rng.uniform(-3, 3)), float(rng.uniform(-math.pi, math.pi))
        )
        start = offset_along(
            dock, -float(rng.uniform(0.5, 1.2)), float(rng.uniform(-0.2, 0.2)), float(rng.uniform(-0.4, 0.4))
        )
        result = simulate_approach(GracefulDockController(dock, params), start, dock, 0.05, timeout_s=20.0)
        assert result.contact, f"run {i}: no contact from {start}"
        assert result.mated, (
            f"run {i}: lateral {result.lateral_error_m:.4f} m, yaw {result.yaw_error_rad:.4f} rad"
        )
        assert np.isfinite(result.trajectory).all()


def test_tuned_controller_is_robust_to_latency_and_noise() -> None:
    sensing_errors = []
    for i, (back, lateral, yaw) in enumerate(
        [(0.7, 0.15, -0.3), (0.7, -0.1, 0.2), (1.0, 0.0, 0.3), (0.6, 0.1, 0.0)]
    ):
        start = offset_along(DOCK, -back, lateral, yaw)
        result = simulate_approach(
            GracefulDockController(DOCK),
            start,
            DOCK,
            0.05,
            sensing=PoseSensing(0.05, 0.002, math.radians(0.2), seed=i),
        )
        assert result.mated
        sensing_errors.append((abs(result.lateral_error_m), abs(result.yaw_error_rad)))
    assert max(lat for lat, _ in sensing_errors) < 0.005
    assert max(yaw for _, yaw in sensing_errors) < math.radians(1.5)


def test_arrival_speed_is_capped_near_the_plate() -> None:
    start = offset_along(DOCK, -1.0, 0.0, 0.0)
    result = simulate_approach(GracefulDockController(DOCK), start, DOCK, 0.05)
    assert result.contact and result.contact_speed_mps == pytest.approx(
        ZENDOCK_PARAMS.contact_speed_mps, abs=0.005
    )
    assert result.trajectory[:, 4].max() > 0.45  # but it is fast on the way


def test_the_plate_is_met_at_the_contact_speed_from_late_noisy_poses_and_braking_late() -> None:
    # Braking hard late is what makes the approach quick; the period a command holds and a few millimetres
    # of pose error must not make the robot meet the plate faster than the contact speed.
    quick = replace(ZENDOCK_PARAMS, pose_estimator=replace(ZENDOCK_PARAMS.pose_estimator, latency_s=0.05))
    speeds, braking_from = [], []
    for i, lateral in enumerate((-0.1, 0.0, 0.1, 0.05)):
        start = offset_along(DOCK, -0.8, lateral, 0.1 * lateral)
        result = simulate_approach(
            GracefulDockController(DOCK, quick),
            start,
            DOCK,
            0.05,
            sensing=PoseSensing(0.05, 0.002, math.radians(0.2), seed=i),
        )
        assert result.mated
        speeds.append(result.contact_speed_mps)
        along = np.array(
            [dock_frame_error(Pose2D(x, y, yaw), DOCK).along_m for _, x, y, yaw, _, _ in result.trajectory]
        )
        fast = result.trajectory[:, 4] > 0.45
        braking_from.append(-along[fast].max())  # the nearest point to the plate still at nearly full speed
    assert max(speeds) <= ZENDOCK_PARAMS.contact_speed_mps + 0.01, speeds
    # nearly full speed until about 0.24 m from the dock pose (its contacts touch 0.05 m short of it), as
    # late as a command the robot could end on allows (held 0.3 s, then braked at 2 m/s2): braking at
    # 0.5 m/s2 it would have slowed from 0.3 m out
    assert max(braking_from) < 0.26, braking_from


def test_target_is_past_the_plate_and_follows_dock_updates() -> None:
    controller = GracefulDockController(DOCK)
    assert dock_frame_error(controller.target, DOCK).along_m == pytest.approx(
        ZENDOCK_PARAMS.dock_target_past_m
    )
    moved = Pose2D(0.0, 0.0, 0.0)
    controller.set_dock_pose(moved)
    assert dock_frame_error(controller.target, moved).along_m == pytest.approx(
        ZENDOCK_PARAMS.dock_target_past_m
    )


def test_distance_test_stops_the_robot() -> None:
    controller = GracefulDockController(DOCK, NAV2_DOCKING_PARAMS)
    assert controller.step(-1.0, 0.86, -math.pi / 2) == (0.0, 0.0)
    assert controller.step(-1.0, 1.5, -math.pi / 2)[0] > 0.0
    assert not GracefulDockController(DOCK).is_docked_by_distance(
        DOCK
    )  # zendock leaves stopping to the caller


def test_estimator_takes_the_callers_timing_and_odometry() -> None:
    start = offset_along(DOCK, -0.7, 0.0, 0.0)
    blocked = GracefulDockController(DOCK)
    assert blocked.compute(start).linear_x_mps > 0.0
    # The base did not move (odometry says so): the estimate stays where the robot is.
    blocked.compute(start, dt_s=0.5, pose_age_s=0.0, base_twist=(0.0, 0.0))
    assert blocked.estimator is not None and blocked.estimator.pose.distance_to(start) < 1e-9
    # Without odometry the estimate follows the last command, ahead of the stale measurement.
    trusting = GracefulDockController(DOCK)
    trusting.compute(start)
    trusting.compute(start, dt_s=0.5)
    assert trusting.estimator is not None and trusting.estimator.pose.distance_to(start) > 0.05
    trusting.reset()
    assert not trusting.estimator.initialised


def test_the_target_recedes_so_it_stays_a_lookahead_ahead() -> None:
    controller = GracefulDockController(DOCK)
    far = offset_along(DOCK, -1.0, 0.02)
    near = offset_along(DOCK, -0.1, 0.02)
    assert dock_frame_error(controller.target_for(far), DOCK).along_m == pytest.approx(
        ZENDOCK_PARAMS.dock_target_past_m
    )
    lookahead = ZENDOCK_PARAMS.target_lookahead_m
    assert lookahead is not None
    assert dock_frame_error(controller.target_for(near), DOCK).along_m == pytest.approx(-0.1 + lookahead)
    fixed = GracefulDockController(DOCK, replace(ZENDOCK_PARAMS, target_lookahead_m=None))
    assert fixed.target_for(near) == fixed.target


def test_beta_eases_off_far_from_the_plate() -> None:
    controller = GracefulDockController(DOCK)
    p = ZENDOCK_PARAMS
    assert p.far_beta is not None
    assert controller.gains_at(offset_along(DOCK, -0.3)).beta == pytest.approx(p.gains.beta)
    assert controller.gains_at(offset_along(DOCK, -1.5)).beta == pytest.approx(p.far_beta)
    middle = 0.5 * (p.near_distance_m + p.far_distance_m)
    assert controller.gains_at(offset_along(DOCK, -middle)).beta == pytest.approx(
        0.5 * (p.gains.beta + p.far_beta)
    )
    # Askew far from the plate, the robot now turns faster than the law's beta alone would let it.
    askew = offset_along(DOCK, -1.0, 0.15, -0.6)
    plain = smooth_control_law(controller.target_for(askew), askew, p.gains)
    assert abs(controller.compute(askew).angular_z_radps) > abs(plain.angular_z_radps)


def test_facing_well_away_it_turns_on_the_spot_first_then_docks() -> None:
    start = offset_along(DOCK, -0.7, 0.0, math.pi / 2)  # at the staging pose, turned a quarter away
    first = GracefulDockController(DOCK).compute(start)
    assert first.linear_x_mps == 0.0 and abs(first.angular_z_radps) > 1.0
    assert first.angular_z_radps < 0.0  # the short way round
    result = simulate_approach(GracefulDockController(DOCK), start, DOCK, 0.05, timeout_s=20.0)
    assert result.mated and abs(result.yaw_error_rad) < math.radians(0.5), result.error
    assert result.time_s < 4.0
    close_by = offset_along(DOCK, -0.2, 0.0, math.pi / 2)  # no turning on the spot next to the dock
    assert GracefulDockController(DOCK).compute(close_by).linear_x_mps > 0.0


def test_the_last_stretch_only_holds_the_docks_heading() -> None:
    controller = GracefulDockController(DOCK, replace(ZENDOCK_PARAMS, pose_estimator=None))
    inside = offset_along(DOCK, -0.1, 0.01, 0.0)  # a centimetre to the side, square to the dock
    command = controller.compute(inside)
    assert command.linear_x_mps > 0.0 and command.angular_z_radps == 0.0  # no swing into yaw for 1 cm
    turned = offset_along(DOCK, -0.1, 0.0, 0.02)
    command = controller.compute(turned)
    assert command.angular_z_radps == pytest.approx(-ZENDOCK_PARAMS.align_gain_per_s * 0.02)
    outside = offset_along(DOCK, -0.4, 0.01, 0.0)
    assert controller.compute(outside).angular_z_radps != 0.0  # the law still steers further out


def test_commands_on_their_way_are_predicted_through() -> None:
    params = replace(ZENDOCK_PARAMS, command_delay_s=0.2, pose_estimator=None)
    controller = GracefulDockController(DOCK, params)
    start = offset_along(DOCK, -1.0)
    for _ in range(4):  # four commands of 0.05 s each are still on their way
        command = controller.compute(start, 0.05)
    assert command.linear_x_mps > 0.3
    predicted = controller.predict_pose(start)
    ahead = dock_frame_error(predicted, DOCK).along_m - dock_frame_error(start, DOCK).along_m
    assert 0.05 < ahead < 0.5 * 0.2 + 1e-9
    controller.forget_commands()  # the robot was held instead: nothing is on its way
    assert controller.predict_pose(start) == start
    assert GracefulDockController(DOCK).predict_pose(start) == start  # the bench default: no delay


def test_the_arrival_cap_is_the_fastest_speed_that_can_still_brake_after_a_held_command() -> None:
    p = replace(ZENDOCK_PARAMS, last_command_hold_s=None)  # the next command comes: the held command's cap
    controller = GracefulDockController(DOCK, p)
    a, contact = p.approach_decel_mps2, p.contact_speed_mps
    period = p.control_period_s * p.arrival_hold_periods  # a command may hold for two ticks
    assert contact is not None
    reach = p.contact_reach_m + p.arrival_margin_m
    for to_contact in np.linspace(0.0, 0.3, 31):
        pose = offset_along(DOCK, -(reach + to_contact), 0.0, 0.0)
        v = controller._cap_arrival_speed(VelocityCommand(0.5, 0.2, 0.4), pose, contact).linear_x_mps
        left = to_contact - v * period  # where the command held for a period leaves the robot
        if v >= 0.5 - 1e-9:  # the command itself is slow enough
            assert v**2 <= contact**2 + 2.0 * a * left
        elif v > contact + 1e-9:
            assert v**2 == pytest.approx(
                contact**2 + 2.0 * a * left
            )  # brakes to the contact speed exactly in time
        else:
            assert v == pytest.approx(contact)  # never slower than the contact speed
    at_plate = controller._cap_arrival_speed(
        VelocityCommand(0.5, 0.2, 0.4), offset_along(DOCK, -reach, 0.0, 0.0), contact
    )
    assert at_plate.linear_x_mps == pytest.approx(contact)
    assert at_plate.curvature_per_m == 0.4 and at_plate.angular_z_radps == pytest.approx(0.4 * contact)


def test_a_command_that_turns_out_to_be_the_last_still_brakes_in_time() -> None:
    # Killed mid-approach, the docking service sends nothing more: the base drives on its last command
    # until its watchdog stops it 0.3 s later. Near the plate the cap is the lower of the two brakings.
    p = ZENDOCK_PARAMS
    assert p.contact_speed_mps is not None and p.last_command_hold_s == 0.3
    controller = GracefulDockController(DOCK)
    reach = p.contact_reach_m + p.arrival_margin_m
    slower_than_held = 0
    for to_contact in np.linspace(0.0, 0.4, 41):
        pose = offset_along(DOCK, -(reach + to_contact), 0.0, 0.0)
        v = controller._cap_arrival_speed(VelocityCommand(0.5, 0.2, 0.4), pose, p.contact_speed_mps)
        held = speed_to_brake_in_time(
            to_contact,
            p.contact_speed_mps,
            p.approach_decel_mps2,
            p.control_period_s * p.arrival_hold_periods,
        )
        last = speed_to_brake_in_time(
            to_contact, p.contact_speed_mps, p.last_command_decel_mps2, p.last_command_hold_s
        )
        assert v.linear_x_mps == pytest.approx(min(0.5, held, last))
        # held 0.3 s, then braked at 2 m/s2: at the plate no faster than the contact speed
        left = to_contact - v.linear_x_mps * p.last_command_hold_s
        assert v.linear_x_mps <= p.contact_speed_mps + 1e-9 or v.linear_x_mps**2 <= (
            p.contact_speed_mps**2 + 2.0 * p.last_command_decel_mps2 * left + 1e-9
        )
        slower_than_held += last < held - 1e-6
    assert slower_than_held > 10  # the watchdog's hold, not the tick's, sets the cap near the plate


class _DiesAt:
    """A controller that stops answering at tick ``tick``: the base holds its last command ``hold_s``, then
    its watchdog stops it (zero commanded; the base brakes at its own limit)."""

    def __init__(self, controller: GracefulDockController, tick: int, dt_s: float, hold_s: float) -> None:
        self._controller, self._tick, self._hold_ticks = controller, tick, round(hold_s / dt_s) - 1
        self._ticks = 0
        self._last = (0.0, 0.0)

    def step(self, x: float, y: float, yaw: float) -> tuple[float, float]:
        self._ticks += 1
        if self._ticks <= self._tick:
            self._last = self._controller.step(x, y, yaw)
            return self._last
        return self._last if self._ticks <= self._tick + self._hold_ticks else (0.0, 0.0)


@pytest.mark.parametrize("hold", [0.3, None], ids=["last-command-capped", "next-command-trusted"])
def test_a_docking_service_killed_anywhere_on_the_approach_never_meets_the_plate_fast(hold) -> None:
    dt = 0.05
    params = replace(ZENDOCK_PARAMS, last_command_hold_s=hold)
    start = offset_along(DOCK, -0.8, 0.02, 0.02)
    whole = simulate_approach(GracefulDockController(DOCK, params), start, DOCK, dt)
    assert whole.contact
    ticks = round(whole.time_s / dt) + 1
    speeds = []
    for tick in range(1, ticks):
        result = simulate_approach(
            _DiesAt(GracefulDockController(DOCK, params), tick, dt, 0.3), start, DOCK, dt, timeout_s=5.0
        )
        if result.contact:
            speeds.append(round(result.contact_speed_mps, 3))
    assert speeds  # killed late enough, the robot still reaches the plate
    if hold is None:
        assert max(speeds) > 0.2, speeds  # the test can fail: trusting the next command, it meets it fast
    else:
        assert max(speeds) <= 0.1, speeds  # a trial's limit (ARRIVAL_SPEED_LIMIT_MPS)
