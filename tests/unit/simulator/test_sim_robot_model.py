"""Diff-drive kinematics and the limits the base enforces."""

from __future__ import annotations

import math

import pytest

from services.simulator.odometry import Odometry, integrate_arc
from services.simulator.robot_model import (
    DiffDrive,
    DiffDriveParams,
    Twist2D,
    WheelSpeeds,
    limit_twist,
    twist_from_wheel_speeds,
    wheel_speeds_from_twist,
)
from shared import structs
from shared.config_errors import ConfigError
from shared.geometry import Pose2D

PARAMS = DiffDriveParams()


def test_wheel_speeds_round_trip_and_signs() -> None:
    wheels = wheel_speeds_from_twist(Twist2D(0.2, 0.5), PARAMS)
    # Turning left: the right wheel runs faster, by w * separation.
    assert wheels.right_radps - wheels.left_radps == pytest.approx(0.5 * 0.26 / 0.033)
    assert 0.5 * (wheels.right_radps + wheels.left_radps) * 0.033 == pytest.approx(0.2)
    back = twist_from_wheel_speeds(wheels, PARAMS)
    assert back.linear_mps == pytest.approx(0.2) and back.angular_radps == pytest.approx(0.5)
    assert twist_from_wheel_speeds(WheelSpeeds(-10.0, 10.0), PARAMS).linear_mps == pytest.approx(0.0)


def test_velocity_clamped_to_limits() -> None:
    fast = Twist2D(PARAMS.max_linear_mps, 0.0)
    out = limit_twist(Twist2D(3.0, 0.0), fast, 0.01, PARAMS)
    assert out.linear_mps == pytest.approx(PARAMS.max_linear_mps)
    spin = Twist2D(0.0, -PARAMS.max_angular_radps)
    assert limit_twist(Twist2D(0.0, -9.0), spin, 0.01, PARAMS).angular_radps == pytest.approx(-1.5)


def test_acceleration_limited_both_ways() -> None:
    drive = DiffDrive(PARAMS)
    previous = Twist2D()
    for _ in range(200):
        out = drive.step(Twist2D(0.5, 1.5), 0.01)
        assert abs(out.linear_mps - previous.linear_mps) <= PARAMS.max_linear_accel * 0.01 + 1e-12
        assert abs(out.angular_radps - previous.angular_radps) <= PARAMS.max_angular_accel * 0.01 + 1e-12
        previous = out
    for _ in range(200):
        out = drive.step(Twist2D(-0.5, -1.5), 0.01)
        assert abs(out.linear_mps - previous.linear_mps) <= PARAMS.max_linear_accel * 0.01 + 1e-12
        previous = out
    assert previous.linear_mps < 0


def test_saturated_wheel_keeps_curvature() -> None:
    steady = Twist2D(0.5, 1.5)
    out = limit_twist(steady, steady, 0.01, PARAMS)
    wheels = wheel_speeds_from_twist(out, PARAMS)
    assert max(abs(wheels.left_radps), abs(wheels.right_radps)) == pytest.approx(PARAMS.max_wheel_speed_radps)
    assert out.linear_mps < 0.5
    assert out.angular_radps / out.linear_mps == pytest.approx(1.5 / 0.5)


def test_non_finite_command_stops() -> None:
    out = limit_twist(Twist2D(math.nan, math.inf), Twist2D(0.0, 0.0), 0.01, PARAMS)
    assert out == Twist2D(0.0, 0.0)


def test_bad_params_rejected() -> None:
    with pytest.raises(ConfigError, match="^drive: wheel_radius_m: must be greater than 0"):
        structs.validate(DiffDriveParams, {"wheel_radius_m": 0.0}, "drive")


def test_integrate_arc_quarter_circle() -> None:
    # A quarter circle of radius 1 to the left from the origin ends at (1, 1) facing +y.
    end = integrate_arc(Pose2D(), math.pi / 2, math.pi / 2)
    assert (end.x, end.y, end.yaw) == pytest.approx((1.0, 1.0, math.pi / 2))


def test_odometry_noise_drifts_only_when_enabled() -> None:
    exact, noisy = Odometry(PARAMS), Odometry(PARAMS, odom_noise=0.05)
    for _ in range(1000):
        exact.update(Twist2D(0.3, 0.0), 0.01)
        noisy.update(Twist2D(0.3, 0.0), 0.01)
    assert (exact.pose.x, exact.pose.y, exact.pose.yaw) == pytest.approx((3.0, 0.0, 0.0), abs=1e-9)
    assert abs(noisy.pose.yaw) > 1e-3 or abs(noisy.pose.x - 3.0) > 1e-3
