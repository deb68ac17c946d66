"""The tf buffer: chains, inverses, interpolation, static links, errors, resets, yaw."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from shared.geometry import Pose2D
from shared.tf_buffer import (
    ConnectivityError,
    ExtrapolationError,
    FrameNotFoundError,
    RigidTransform,
    TfBuffer,
    TransformError,
    slerp,
)


def planar(x: float, y: float, yaw: float) -> RigidTransform:
    return RigidTransform.from_pose2d(Pose2D(x, y, yaw))


def assert_pose(actual: Pose2D, expected: Pose2D, tol: float = 1e-9) -> None:
    assert actual.x == pytest.approx(expected.x, abs=tol)
    assert actual.y == pytest.approx(expected.y, abs=tol)
    assert math.remainder(actual.yaw - expected.yaw, 2 * math.pi) == pytest.approx(0.0, abs=tol)


def matrix(transform: RigidTransform) -> np.ndarray:
    """Homogeneous 4x4 matrix, from the textbook quaternion-to-rotation formula (independent of the buffer)."""
    x, y, z, w = transform.rotation
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    out = np.eye(4)
    out[:3, :3] = rotation
    out[:3, 3] = transform.translation
    return out


def random_transform(rng: random.Random) -> RigidTransform:
    q = [rng.gauss(0.0, 1.0) for _ in range(4)]
    norm = math.sqrt(sum(v * v for v in q))
    return RigidTransform(
        (rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3)),
        tuple(v / norm for v in q),  # type: ignore[arg-type]
    )


MAP_TO_ODOM = Pose2D(1.0, 2.0, 0.5)
ODOM_TO_BASE = Pose2D(0.5, -0.3, 2.9)
BASE_TO_LIDAR = Pose2D(0.1, 0.0, 0.0)


@pytest.fixture
def robot_tree() -> TfBuffer:
    """map -> odom -> base_link -> {lidar_link, ultrasonic_link}, the odometry chain dynamic at t = 5 and 6."""
    buffer = TfBuffer()
    buffer.set_transform("map", "odom", 5.0, planar(*MAP_TO_ODOM.as_tuple()))
    buffer.set_transform("map", "odom", 6.0, planar(*MAP_TO_ODOM.as_tuple()))
    buffer.set_transform("odom", "base_link", 5.0, planar(*ODOM_TO_BASE.as_tuple()))
    buffer.set_transform("odom", "base_link", 6.0, planar(*ODOM_TO_BASE.as_tuple()))
    buffer.set_transform("base_link", "lidar_link", 0.0, planar(*BASE_TO_LIDAR.as_tuple()), static=True)
    buffer.set_transform("base_link", "ultrasonic_link", 0.0, planar(0.2, 0.05, 0.0), static=True)
    return buffer


def test_chain_lookup_composes_the_links(robot_tree: TfBuffer) -> None:
    result = robot_tree.lookup("map", "base_link")
    assert (result.parent_frame, result.child_frame, result.stamp_s) == ("map", "base_link", 6.0)
    assert_pose(result.transform.to_pose2d(), MAP_TO_ODOM.compose(ODOM_TO_BASE))
    assert -math.pi <= result.transform.yaw_rad() < math.pi  # 0.5 + 2.9 wraps to 3.4 - 2 pi


def test_lookup_through_a_static_link(robot_tree: TfBuffer) -> None:
    lidar = robot_tree.lookup("map", "lidar_link").transform.to_pose2d()
    assert_pose(lidar, MAP_TO_ODOM.compose(ODOM_TO_BASE).compose(BASE_TO_LIDAR))


def test_inverse_lookup_is_the_inverse(robot_tree: TfBuffer) -> None:
    forward = robot_tree.lookup("map", "base_link").transform
    backward = robot_tree.lookup("base_link", "map").transform
    assert_pose(backward.to_pose2d(), forward.to_pose2d().inverse())
    assert np.allclose(matrix(forward) @ matrix(backward), np.eye(4))


def test_siblings_meet_at_their_common_parent(robot_tree: TfBuffer) -> None:
    sonar_in_lidar = robot_tree.lookup("lidar_link", "ultrasonic_link").transform.to_pose2d()
    assert_pose(sonar_in_lidar, Pose2D(0.1, 0.05, 0.0))
    # Only static links between them: timeless, stamp 0 as tf2 gives it.
    assert robot_tree.lookup("lidar_link", "ultrasonic_link").stamp_s == 0.0


def test_same_frame_is_identity() -> None:
    result = TfBuffer().lookup("map", "map")
    assert result.transform == RigidTransform()


def test_three_dimensional_chains_match_matrix_products() -> None:
    """Law: composing and inverting along any tree equals the product of the link matrices."""
    rng = random.Random(3)
    for _ in range(50):
        buffer = TfBuffer()
        links = {name: random_transform(rng) for name in ("b", "c", "d", "e")}
        buffer.set_transform("a", "b", 1.0, links["b"])
        buffer.set_transform("b", "c", 1.0, links["c"])
        buffer.set_transform("a", "d", 1.0, links["d"], static=True)
        buffer.set_transform("d", "e", 1.0, links["e"])
        a_from_c = matrix(links["b"]) @ matrix(links["c"])
        a_from_e = matrix(links["d"]) @ matrix(links["e"])
        expected = np.linalg.inv(a_from_e) @ a_from_c
        assert np.allclose(matrix(buffer.lookup("e", "c").transform), expected, atol=1e-9)
        point = (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1))
        moved = buffer.lookup("a", "c").transform.transform_point(point)
        assert np.allclose(moved, (a_from_c @ np.array([*point, 1.0]))[:3], atol=1e-9)


def test_interpolates_translation_linearly_and_rotation_by_slerp() -> None:
    buffer = TfBuffer()
    buffer.set_transform("odom", "base_link", 1.0, planar(0.0, 0.0, 0.0))
    buffer.set_transform("odom", "base_link", 2.0, planar(1.0, -2.0, math.pi / 2))
    result = buffer.lookup("odom", "base_link", 1.25)
    assert result.stamp_s == 1.25
    assert_pose(result.transform.to_pose2d(), Pose2D(0.25, -0.5, math.pi / 8))


def test_slerp_takes_the_short_way_across_pi() -> None:
    buffer = TfBuffer()
    buffer.set_transform("odom", "base_link", 0.0, planar(0.0, 0.0, 3.0))
    buffer.set_transform("odom", "base_link", 1.0, planar(0.0, 0.0, -3.0))
    mid = buffer.lookup("odom", "base_link", 0.5).transform.yaw_rad()
    assert abs(abs(mid) - math.pi) < 1e-9  # through pi, not through 0
    quarter = slerp(planar(0, 0, 3.0).rotation, planar(0, 0, -3.0).rotation, 0.25)
    assert RigidTransform(rotation=quarter).yaw_rad() == pytest.approx(3.0 + 0.25 * (2 * math.pi - 6.0))


def test_latest_common_time_is_the_oldest_newest_stamp_on_the_path() -> None:
    buffer = TfBuffer()
    buffer.set_transform("map", "odom", 4.0, planar(0.0, 0.0, 0.0))
    buffer.set_transform("map", "odom", 5.0, planar(1.0, 0.0, 0.0))
    buffer.set_transform("odom", "base_link", 4.0, planar(0.0, 0.0, 0.0))
    buffer.set_transform("odom", "base_link", 6.0, planar(0.0, 2.0, 0.0))
    buffer.set_transform("base_link", "lidar_link", 0.0, planar(0.1, 0.0, 0.0), static=True)
    assert buffer.latest_common_time("map", "lidar_link") == 5.0
    result = buffer.lookup("map", "lidar_link")
    assert result.stamp_s == 5.0
    assert_pose(result.transform.to_pose2d(), Pose2D(1.1, 1.0, 0.0))  # odom -> base_link halfway


def test_static_links_hold_at_any_time() -> None:
    buffer = TfBuffer()
    buffer.set_transform("base_link", "lidar_link", 0.0, planar(0.1, 0.0, 0.0), static=True)
    for time_s in (0.0, 1e3, 1e6):
        assert_pose(
            buffer.lookup("base_link", "lidar_link", time_s).transform.to_pose2d(), Pose2D(0.1, 0.0, 0.0)
        )


def test_extrapolation_into_the_future_and_the_past_name_the_link(robot_tree: TfBuffer) -> None:
    with pytest.raises(ExtrapolationError, match=r"future.*odom -> base_link") as future:
        robot_tree.lookup("odom", "base_link", 7.0)
    with pytest.raises(ExtrapolationError, match=r"past.*odom -> base_link"):
        robot_tree.lookup("odom", "base_link", 4.0)
    assert isinstance(future.value, LookupError)


def test_a_link_whose_history_ends_before_another_begins_cannot_be_looked_up_at_latest() -> None:
    buffer = TfBuffer()
    buffer.set_transform("map", "odom", 1.0, planar(0.0, 0.0, 0.0))
    buffer.set_transform("odom", "base_link", 3.0, planar(0.0, 0.0, 0.0))
    with pytest.raises(ExtrapolationError, match="odom -> base_link"):
        buffer.lookup("map", "base_link")


def test_missing_frame_is_named() -> None:
    buffer = TfBuffer()
    with pytest.raises(FrameNotFoundError, match="'map' does not exist.*none yet"):
        buffer.lookup("map", "base_link")
    buffer.set_transform("odom", "base_link", 1.0, planar(0.0, 0.0, 0.0))
    with pytest.raises(FrameNotFoundError, match=r"'map' does not exist \(known frames: base_link, odom\)"):
        buffer.lookup("map", "base_link")


def test_unconnected_trees_name_their_roots() -> None:
    buffer = TfBuffer()
    buffer.set_transform("odom", "base_link", 1.0, planar(0.0, 0.0, 0.0))
    buffer.set_transform("map", "dock", 1.0, planar(0.0, 0.0, 0.0), static=True)
    with pytest.raises(ConnectivityError, match=r"base_link's tree ends at 'odom' and map's at 'map'"):
        buffer.lookup("map", "base_link")
    assert not buffer.can_transform("map", "base_link")


def test_time_going_back_clears_dynamic_history_and_keeps_static(robot_tree: TfBuffer) -> None:
    assert robot_tree.set_transform("odom", "base_link", 6.5, planar(0.0, 0.0, 0.0)) is False
    assert robot_tree.set_transform("odom", "base_link", 0.2, planar(3.0, 0.0, 0.0)) is True
    assert robot_tree.parent_of("odom") is None  # map -> odom went with the reset
    with pytest.raises(ExtrapolationError):
        robot_tree.lookup("odom", "base_link", 6.0)
    assert_pose(robot_tree.lookup("odom", "lidar_link").transform.to_pose2d(), Pose2D(3.1, 0.0, 0.0))


def test_small_reordering_is_not_a_reset() -> None:
    buffer = TfBuffer()
    buffer.set_transform("odom", "base_link", 2.0, planar(2.0, 0.0, 0.0))
    assert buffer.set_transform("odom", "base_link", 1.5, planar(1.5, 0.0, 0.0)) is False
    assert_pose(buffer.lookup("odom", "base_link", 1.75).transform.to_pose2d(), Pose2D(1.75, 0.0, 0.0))


def test_history_older_than_the_cache_is_dropped() -> None:
    buffer = TfBuffer(cache_time_s=10.0, time_jump_reset_s=1.0)
    for stamp in range(21):
        buffer.set_transform("odom", "base_link", float(stamp), planar(float(stamp), 0.0, 0.0))
    assert buffer.can_transform("odom", "base_link", 10.0)
    with pytest.raises(ExtrapolationError, match="past"):
        buffer.lookup("odom", "base_link", 9.5)


def test_yaw_is_wrapped_to_minus_pi_up_to_pi() -> None:
    assert RigidTransform(rotation=(0.0, 0.0, 1.0, 0.0)).yaw_rad() == -math.pi  # a half turn reads -pi
    rng = random.Random(11)
    for _ in range(200):
        yaw = rng.uniform(-20.0, 20.0)
        got = planar(0.0, 0.0, yaw).yaw_rad()
        assert -math.pi <= got < math.pi
        assert math.remainder(got - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_rejects_malformed_transforms() -> None:
    buffer = TfBuffer()
    with pytest.raises(ValueError, match="no direction"):
        buffer.set_transform("odom", "base_link", 1.0, RigidTransform(rotation=(0.0, 0.0, 0.0, 0.0)))
    with pytest.raises(ValueError, match="to itself"):
        buffer.set_transform("odom", "/odom", 1.0, RigidTransform())
    with pytest.raises(ValueError, match="empty"):
        buffer.set_transform("", "base_link", 1.0, RigidTransform())
    with pytest.raises(ValueError, match="non-finite"):
        buffer.set_transform("odom", "base_link", math.nan, RigidTransform())
    assert buffer.frames() == set()


def test_leading_slashes_and_unnormalised_quaternions_are_accepted() -> None:
    buffer = TfBuffer()
    buffer.set_transform("/odom", "/base_link", 1.0, RigidTransform((1.0, 0.0, 0.0), (0.0, 0.0, 2.0, 2.0)))
    assert_pose(buffer.lookup("odom", "base_link").transform.to_pose2d(), Pose2D(1.0, 0.0, math.pi / 2))


def test_a_new_parent_replaces_the_old_link() -> None:
    buffer = TfBuffer()
    buffer.set_transform("odom", "base_link", 1.0, planar(1.0, 0.0, 0.0))
    buffer.set_transform("map", "base_link", 1.0, planar(2.0, 0.0, 0.0))
    assert buffer.parent_of("base_link") == "map"
    assert_pose(buffer.lookup("map", "base_link").transform.to_pose2d(), Pose2D(2.0, 0.0, 0.0))


def test_errors_are_lookup_errors() -> None:
    assert issubclass(TransformError, LookupError)
    for cls in (FrameNotFoundError, ConnectivityError, ExtrapolationError):
        assert issubclass(cls, TransformError)
