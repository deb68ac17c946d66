"""SE(2) and quaternion helpers."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from shared.geometry import (
    Pose2D,
    euler_from_quaternion,
    quaternion_from_yaw,
    quaternion_multiply,
    wrap_angle,
    wrap_angles,
    yaw_from_quaternion,
)


@pytest.mark.parametrize("angle", [0.0, math.pi / 2, -math.pi / 2, 3.0, -3.0, 7.0, -7.0, 100.0])
def test_wrap_angle_range_and_equivalence(angle: float) -> None:
    wrapped = wrap_angle(angle)
    assert -math.pi <= wrapped < math.pi
    assert math.cos(wrapped) == pytest.approx(math.cos(angle)) and math.sin(wrapped) == pytest.approx(
        math.sin(angle)
    )
    assert wrap_angles(np.array([angle]))[0] == pytest.approx(wrapped)


def test_yaw_quaternion_round_trip_matches_euler() -> None:
    rng = random.Random(1)
    for _ in range(200):
        yaw = rng.uniform(-math.pi, math.pi)
        q = quaternion_from_yaw(yaw)
        assert yaw_from_quaternion(*q) == pytest.approx(yaw, abs=1e-12)
        roll, pitch, yaw2 = euler_from_quaternion(*q)
        assert (roll, pitch) == (pytest.approx(0.0), pytest.approx(0.0)) and yaw2 == pytest.approx(
            yaw, abs=1e-12
        )


def test_euler_pitch_clamped() -> None:
    _, pitch, _ = euler_from_quaternion(0.0, math.sqrt(0.5) + 1e-9, 0.0, math.sqrt(0.5) + 1e-9)
    assert pitch == pytest.approx(math.pi / 2, abs=1e-4)


def test_quaternion_multiply_adds_yaw() -> None:
    q = quaternion_multiply(quaternion_from_yaw(0.4), quaternion_from_yaw(0.5))
    assert yaw_from_quaternion(*q) == pytest.approx(0.9)


def test_compose_inverse_identity() -> None:
    rng = random.Random(2)
    for _ in range(100):
        a = Pose2D(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-3, 3))
        b = Pose2D(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-3, 3))
        ident = a.compose(a.inverse())
        assert (ident.x, ident.y, ident.yaw) == (
            pytest.approx(0, abs=1e-9),
            pytest.approx(0, abs=1e-9),
            pytest.approx(0, abs=1e-9),
        )
        rel = b.relative_to(a)
        back = a.compose(rel)
        assert (back.x, back.y) == (pytest.approx(b.x), pytest.approx(b.y))
        assert wrap_angle(back.yaw - b.yaw) == pytest.approx(0, abs=1e-9)


def test_compose_matches_matrices() -> None:
    a, b = Pose2D(1.0, 2.0, 0.3), Pose2D(-0.5, 0.2, -1.1)
    np.testing.assert_allclose(a.compose(b).matrix(), a.matrix() @ b.matrix(), atol=1e-12)


def test_transform_points() -> None:
    pose = Pose2D(1.0, 0.0, math.pi / 2)
    np.testing.assert_allclose(
        pose.transform_points(np.array([[1.0, 0.0], [0.0, 1.0]])), [[1.0, 1.0], [0.0, 0.0]], atol=1e-12
    )
    assert pose.transform_point(1.0, 0.0) == pytest.approx((1.0, 1.0))


def _same_pose(a: Pose2D, b: Pose2D, tol_m: float = 1e-6, tol_rad: float = 1e-6) -> bool:
    return a.distance_to(b) < tol_m and abs(math.remainder(a.yaw - b.yaw, 2 * math.pi)) < tol_rad


def test_advance_follows_the_exact_arc_and_straight_lines() -> None:
    radius_m = 2 / math.pi
    quarter = Pose2D().advance(1.0, math.pi / 2, 1.0)  # a quarter circle
    assert _same_pose(quarter, Pose2D(radius_m, radius_m, math.pi / 2))
    assert _same_pose(Pose2D(0, 0, math.pi / 2).advance(2.0, 0.0, 0.5), Pose2D(0.0, 1.0, math.pi / 2))
    # Many small steps along the arc land where one long step does: nothing is lost to integration.
    pose = Pose2D(1.0, -2.0, 0.3)
    stepped = pose
    for _ in range(100):
        stepped = stepped.advance(0.4, -1.1, 0.03)
    assert _same_pose(stepped, pose.advance(0.4, -1.1, 3.0), tol_m=1e-9, tol_rad=1e-9)
    assert _same_pose(pose.advance(0.4, 1.0, 0.0), pose)


def test_interpolate_goes_the_shorter_way_round() -> None:
    mid = Pose2D(0, 0, 3.0).interpolate(Pose2D(2, 0, -3.0), 0.5)  # across +-pi, not through 0
    assert _same_pose(mid, Pose2D(1.0, 0.0, -math.pi), tol_rad=1e-9)
    a, b = Pose2D(1, 2, 0.1), Pose2D(3, -2, 0.5)
    assert _same_pose(a.interpolate(b, 0.0), a) and _same_pose(a.interpolate(b, 1.0), b)
