import math

import numpy as np
import pytest

from services.docking.kinematics import DiffDriveModel, PoseSensing, RobotLimits, simulate_approach
from shared.geometry import Pose2D


def test_linear_acceleration_is_limited() -> None:
    robot = DiffDriveModel(Pose2D(), RobotLimits(a_max_mps2=1.0))
    for _ in range(50):
        robot.step(2.0, 0.0, 0.01)  # asks for more than v_max
    assert robot.v_mps == pytest.approx(0.5)
    assert robot.x == pytest.approx(0.125 + 0.5 * 0.005, abs=1e-3)  # ramp 0 -> 0.5 m/s over 0.5 s
    for _ in range(50):
        robot.step(2.0, 0.0, 0.01)
    assert robot.v_mps == pytest.approx(0.5) and robot.x == pytest.approx(0.375 + 0.0025, abs=2e-3)


def test_braking_is_harder_than_speeding_up_as_on_the_simulated_base() -> None:
    robot = DiffDriveModel(Pose2D(), RobotLimits(a_max_mps2=1.0, a_decel_mps2=2.5, alpha_decel_radps2=6.0))
    robot.v_mps, robot.w_radps = 0.5, 1.5
    robot.step(0.0, 0.0, 0.1)
    assert (robot.v_mps, robot.w_radps) == pytest.approx((0.25, 0.9))
    robot.step(-0.5, -1.5, 0.1)  # reversing is speeding up the other way once past zero
    assert (robot.v_mps, robot.w_radps) == pytest.approx((0.15, 0.6))


def test_the_model_limits_a_twist_as_the_simulated_base_does_short_of_the_wheels_own_limit() -> None:
    from services.simulator.robot_model import DiffDriveParams, Twist2D, limit_twist

    base = DiffDriveParams()
    limits = RobotLimits()
    assert (
        limits.v_max_mps,
        limits.w_max_radps,
        limits.a_max_mps2,
        limits.alpha_max_radps2,
        limits.a_decel_mps2,
        limits.alpha_decel_radps2,
    ) == (
        base.max_linear_mps,
        base.max_angular_radps,
        base.max_linear_accel,
        base.max_angular_accel,
        base.max_linear_decel,
        base.max_angular_decel,
    )
    rng = np.random.default_rng(3)
    compared = 0
    for _ in range(2000):
        v, w, cmd_v, cmd_w = (
            rng.uniform(-0.6, 0.6),
            rng.uniform(-1.8, 1.8),
            rng.uniform(-0.7, 0.7),
            rng.uniform(-2, 2),
        )
        dt = rng.choice([0.005, 0.01, 0.05])
        model = limits.next_twist(v, w, cmd_v, cmd_w, dt)
        half_track = 0.5 * base.wheel_separation_m
        if abs(model[0]) + abs(model[1]) * half_track > base.max_linear_mps:
            continue  # a wheel at its limit: the simulator scales both down, the model does not
        delivered = limit_twist(Twist2D(cmd_v, cmd_w), Twist2D(v, w), dt, base)
        assert model == pytest.approx((delivered.linear_mps, delivered.angular_radps), abs=1e-12)
        compared += 1
    assert compared > 500
    assert limits.next_twist(0.3, 0.5, math.nan, math.inf, 0.1) == pytest.approx((0.05, 0.0))


def test_angular_acceleration_and_rate_are_limited() -> None:
    robot = DiffDriveModel(Pose2D(), RobotLimits(alpha_max_radps2=3.0, w_max_radps=1.5))
    robot.step(0.0, -10.0, 0.1)
    assert robot.w_radps == pytest.approx(-0.3)
    for _ in range(20):
        robot.step(0.0, -10.0, 0.1)
    assert robot.w_radps == pytest.approx(-1.5)


def test_constant_twist_follows_a_circle() -> None:
    robot = DiffDriveModel(Pose2D(0.0, 0.0, 0.0))
    robot.v_mps, robot.w_radps = 0.5, 1.0  # already moving: radius 0.5 m about (0, 0.5)
    for _ in range(100):
        robot.step(0.5, 1.0, 0.01)
    assert math.hypot(robot.x, robot.y - 0.5) == pytest.approx(0.5, abs=1e-9)
    assert robot.pose.yaw == pytest.approx(1.0)


class SeenPoses:
    def __init__(self, command: tuple[float, float]) -> None:
        self.command = command
        self.seen: list[tuple[float, float, float]] = []

    def step(self, x: float, y: float, yaw: float) -> tuple[float, float]:
        self.seen.append((x, y, yaw))
        return self.command


def test_controller_sees_the_pose_late() -> None:
    dock = Pose2D(10.0, 0.0, 0.0)
    controller = SeenPoses((0.3, 0.0))
    result = simulate_approach(
        controller, Pose2D(), dock, 0.1, sensing=PoseSensing(latency_s=0.2), timeout_s=2.0
    )
    traj = result.trajectory
    assert controller.seen[0][0] == controller.seen[1][0] == controller.seen[2][0] == 0.0
    for tick in (5, 10, 15):
        t_seen = tick * 0.1 - 0.2
        row = int(round(t_seen / 0.005))
        assert traj[row, 0] == pytest.approx(t_seen)
        assert controller.seen[tick][0] == pytest.approx(traj[row, 1])


def test_contact_ends_the_run_with_errors_in_the_dock_frame() -> None:
    dock = Pose2D(1.0, 0.02, 0.05)
    result = simulate_approach(SeenPoses((0.2, 0.0)), Pose2D(), dock, 0.05)
    assert result.contact and result.mated
    assert result.error.along_m == pytest.approx(-0.05, abs=0.002)
    assert result.yaw_error_rad == pytest.approx(-0.05)
    assert result.contact_speed_mps == pytest.approx(0.2)


def test_misaligned_contact_does_not_mate() -> None:
    result = simulate_approach(SeenPoses((0.2, 0.0)), Pose2D(0.0, 0.1, 0.0), Pose2D(1.0, 0.0, 0.0), 0.05)
    assert result.contact and not result.mated
    assert result.lateral_error_m == pytest.approx(0.1)


def test_stopped_controller_ends_the_run_without_contact() -> None:
    result = simulate_approach(SeenPoses((0.0, 0.0)), Pose2D(), Pose2D(5.0, 0.0, 0.0), 0.1, stopped_for_s=0.5)
    assert not result.contact and not result.mated
    assert result.time_s == pytest.approx(0.6, abs=0.11)


def test_non_finite_command_is_an_error() -> None:
    with pytest.raises(ValueError, match="non-finite"):
        simulate_approach(SeenPoses((float("nan"), 0.0)), Pose2D(), Pose2D(1.0, 0.0, 0.0), 0.1)
