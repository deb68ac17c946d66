import math

import numpy as np
import pytest

from services.docking.pose_filter import DockPoseFilter, PoseFilterParams
from shared.geometry import Pose2D


def same(a: Pose2D | None, b: Pose2D) -> bool:
    return a is not None and a.as_tuple() == pytest.approx(b.as_tuple(), abs=1e-12)


def test_first_detection_is_taken_as_is() -> None:
    f = DockPoseFilter()
    assert f.pose is None and not f.is_fresh(0.0)
    assert same(f.update(Pose2D(1.0, 2.0, 0.5), 10.0), Pose2D(1.0, 2.0, 0.5))
    assert f.stamp_s == 10.0 and f.is_fresh(10.9) and not f.is_fresh(11.1)


def test_exponential_smoothing_of_position_and_yaw() -> None:
    f = DockPoseFilter(PoseFilterParams(coef=0.1))
    f.update(Pose2D(0.0, 0.0, 0.0), 0.0)
    out = f.update(Pose2D(0.1, -0.2, 0.2), 0.1)
    assert (out.x, out.y, out.yaw) == pytest.approx((0.01, -0.02, 0.02))
    out = f.update(Pose2D(0.1, -0.2, 0.2), 0.2)
    assert (out.x, out.y, out.yaw) == pytest.approx((0.019, -0.038, 0.038))


def test_yaw_is_smoothed_along_the_short_arc_across_pi() -> None:
    f = DockPoseFilter(PoseFilterParams(coef=0.5))
    f.update(Pose2D(0.0, 0.0, math.pi - 0.1), 0.0)
    out = f.update(Pose2D(0.0, 0.0, -math.pi + 0.1), 0.05)
    assert abs(abs(out.yaw) - math.pi) < 1e-9  # half way along the 0.2 rad arc through pi, not through 0


def test_noise_is_reduced() -> None:
    rng = np.random.default_rng(3)
    f = DockPoseFilter(PoseFilterParams(coef=0.1))
    truth = Pose2D(2.0, -1.0, 0.4)
    errors = []
    for i in range(300):
        noisy = Pose2D(
            truth.x + rng.normal(0, 0.01), truth.y + rng.normal(0, 0.01), truth.yaw + rng.normal(0, 0.02)
        )
        out = f.update(noisy, i * 0.05)
        if i > 50:
            errors.append(out.distance_to(truth))
    assert float(np.std(errors)) < 0.006 and max(errors) < 0.015


def test_restarts_after_a_gap_longer_than_the_timeout() -> None:
    f = DockPoseFilter(PoseFilterParams(coef=0.1, timeout_s=1.0))
    f.update(Pose2D(0.0, 0.0, 0.0), 0.0)
    f.update(Pose2D(0.1, 0.0, 0.0), 0.9)
    assert f.pose is not None and f.pose.x == pytest.approx(0.01)
    assert same(f.update(Pose2D(0.2, 0.0, 0.1), 2.0), Pose2D(0.2, 0.0, 0.1))


def test_older_detections_are_ignored() -> None:
    f = DockPoseFilter()
    f.update(Pose2D(0.0, 0.0, 0.0), 5.0)
    assert same(f.update(Pose2D(0.2, 0.0, 0.0), 4.5), Pose2D(0.0, 0.0, 0.0))
    assert f.stamp_s == 5.0


def test_outliers_are_rejected_until_they_persist() -> None:
    f = DockPoseFilter(
        PoseFilterParams(coef=0.5, outlier_distance_m=0.2, outlier_yaw_rad=0.3, max_rejected_in_a_row=3)
    )
    f.update(Pose2D(0.0, 0.0, 0.0), 0.0)
    assert same(f.update(Pose2D(1.0, 0.0, 0.0), 0.1), Pose2D(0.0, 0.0, 0.0))
    assert same(f.update(Pose2D(0.0, 0.0, 1.0), 0.2), Pose2D(0.0, 0.0, 0.0))
    assert f.rejected_in_a_row == 2
    assert f.update(Pose2D(0.02, 0.0, 0.0), 0.3).x == pytest.approx(0.01)  # a good one clears the count
    assert f.rejected_in_a_row == 0
    for t in (0.4, 0.5):
        f.update(Pose2D(1.0, 1.0, 0.0), t)
    assert same(f.update(Pose2D(1.0, 1.0, 0.0), 0.6), Pose2D(1.0, 1.0, 0.0))  # third in a row: the dock moved


def test_outlier_rejection_can_be_disabled_and_coef_zero_passes_through() -> None:
    f = DockPoseFilter(PoseFilterParams(coef=0.5, outlier_distance_m=None, outlier_yaw_rad=None))
    f.update(Pose2D(0.0, 0.0, 0.0), 0.0)
    assert f.update(Pose2D(2.0, 0.0, 0.0), 0.1).x == pytest.approx(1.0)
    raw = DockPoseFilter(PoseFilterParams(coef=0.0))
    raw.update(Pose2D(0.0, 0.0, 0.0), 0.0)
    assert same(raw.update(Pose2D(0.3, 0.1, 0.2), 0.1), Pose2D(0.3, 0.1, 0.2))
    f.reset()
    assert f.pose is None


def test_params_are_validated() -> None:
    with pytest.raises(ValueError):
        PoseFilterParams(coef=1.5)
    with pytest.raises(ValueError):
        PoseFilterParams(timeout_s=0.0)
    with pytest.raises(ValueError):
        PoseFilterParams(max_rejected_in_a_row=0)
