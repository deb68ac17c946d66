import math

import numpy as np
import pytest

from services.docking.kinematics import DiffDriveModel, RobotLimits
from services.docking.pose_estimator import PoseEstimatorParams, RobotPoseEstimator
from shared.geometry import Pose2D


def test_first_measurement_initialises() -> None:
    est = RobotPoseEstimator()
    assert not est.initialised
    with pytest.raises(RuntimeError):
        est.propagate(0.1, 0.0, 0.1)
    assert est.correct(Pose2D(1.0, 2.0, 0.3)).as_tuple() == pytest.approx((1.0, 2.0, 0.3))
    assert est.velocity == (0.0, 0.0)


def test_propagation_matches_the_base_model() -> None:
    limits = RobotLimits()
    est = RobotPoseEstimator(PoseEstimatorParams(command_limits=limits))
    est.reset(Pose2D(0.0, 0.0, 0.2))
    robot = DiffDriveModel(Pose2D(0.0, 0.0, 0.2), limits)
    for i in range(40):
        v, w = 0.5, (1.0 if i < 20 else -1.0)
        est.propagate(v, w, 0.05)
        for _ in range(10):
            robot.step(v, w, 0.005)
    assert est.pose.distance_to(robot.pose) < 2e-3
    assert est.pose.yaw == pytest.approx(robot.pose.yaw, abs=5e-3)


def test_without_limits_the_velocity_is_followed_at_once() -> None:
    est = RobotPoseEstimator(PoseEstimatorParams(command_limits=None))
    est.reset(Pose2D())
    est.propagate(0.4, 0.0, 0.5)
    assert est.pose.x == pytest.approx(0.2) and est.velocity == (0.4, 0.0)


def test_compensates_latency_and_smooths_noise() -> None:
    latency_s, dt = 0.05, 0.05
    rng = np.random.default_rng(11)
    est = RobotPoseEstimator(PoseEstimatorParams(correction_gain=0.12, latency_s=latency_s))
    robot = DiffDriveModel(Pose2D(0.0, 0.0, 0.0))
    history = [robot.pose]
    raw_errors, est_errors = [], []
    command = (0.0, 0.0)
    for tick in range(120):
        command = (0.4, 0.3 * math.sin(tick * 0.1))
        if est.initialised:
            est.propagate(*command, dt)
        lagged = history[max(0, len(history) - 1 - round(latency_s / dt))]
        measured = Pose2D(lagged.x + rng.normal(0, 0.002), lagged.y + rng.normal(0, 0.002), lagged.yaw)
        estimate = est.correct(measured)
        if tick > 40:
            raw_errors.append(measured.distance_to(robot.pose))
            est_errors.append(estimate.distance_to(robot.pose))
        for _ in range(10):
            robot.step(*command, dt / 10)
        history.append(robot.pose)
    # The raw pose is 20 mm behind at 0.4 m/s; the estimate is within a couple of millimetres.
    assert float(np.median(raw_errors)) > 0.015
    assert float(np.median(est_errors)) < 0.003


def test_gain_one_and_no_latency_trusts_the_measurement() -> None:
    est = RobotPoseEstimator(PoseEstimatorParams(correction_gain=1.0, latency_s=0.0, command_limits=None))
    est.reset(Pose2D())
    est.propagate(1.0, 0.0, 0.1)
    assert est.correct(Pose2D(0.5, 0.5, 0.5)).as_tuple() == pytest.approx((0.5, 0.5, 0.5))


def test_params_are_validated() -> None:
    with pytest.raises(ValueError):
        PoseEstimatorParams(correction_gain=0.0)
    with pytest.raises(ValueError):
        PoseEstimatorParams(latency_s=-0.1)


def test_measured_velocity_is_followed_as_is_and_age_overrides_latency() -> None:
    est = RobotPoseEstimator(PoseEstimatorParams(correction_gain=1.0, latency_s=0.1))
    est.reset(Pose2D())
    est.propagate(0.4, 0.0, 0.5, measured_velocity=True)  # no acceleration ramp for measured velocities
    assert est.pose.x == pytest.approx(0.2)
    assert est.correct(Pose2D(0.25, 0.0, 0.0), age_s=0.0).x == pytest.approx(0.25)
    # Default age (0.1 s): the measurement is compared with the track 0.1 s ago (x = 0.2 - 0.04).
    assert est.correct(Pose2D(0.25, 0.0, 0.0)).x == pytest.approx(0.25 + (0.25 - 0.21))
