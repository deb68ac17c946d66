"""The pose track places the robot at any recent instant from a slow map pose and fast odometry.

The planner's uses; the docking service's are in ``tests/unit/docking/test_docking_perception.py``.
"""

from __future__ import annotations

import math

import pytest

from shared.geometry import Pose2D
from shared.pose_tracking import OdometrySample, PoseTrack

#: map -> odom of a localiser that is off by a fixed transform.
MAP_TO_ODOM = Pose2D(1.0, -2.0, 0.3)
#: Odometry older than this is stale (the planner's pose_timeout_s).
ODOM_MAX_AGE_S = 0.5


def _turning(t: float) -> Pose2D:
    """odom -> base_link of a robot driving a circle: 0.4 m/s, 1.2 rad/s from the odom origin."""
    return Pose2D().advance(0.4, 1.2, t)


def _feed(tracker: PoseTrack, until_s: float, map_every: int = 5) -> None:
    """Odometry at 50 Hz, a map pose every ``map_every`` samples, all arriving when stamped."""
    for i in range(int(round(until_s * 50)) + 1):
        t = i / 50
        tracker.add_odom(OdometrySample(t, _turning(t), 0.4, 1.2), received_s=t)
        if i % map_every == 0:
            tracker.add_pose(t, MAP_TO_ODOM.compose(_turning(t)))


def _close(a: Pose2D, b: Pose2D, tol_m: float = 1e-6, tol_rad: float = 1e-6) -> bool:
    return a.distance_to(b) < tol_m and abs(math.remainder(a.yaw - b.yaw, 2 * math.pi)) < tol_rad


def test_pose_at_a_sensor_stamp_between_map_poses_is_exact() -> None:
    tracker = PoseTrack()
    _feed(tracker, 1.0)
    for stamp in (0.63, 0.8, 0.97, 1.0):
        expected = MAP_TO_ODOM.compose(_turning(stamp))
        got = tracker.pose_now_at(stamp)
        assert got is not None and _close(got, expected, tol_m=2e-3, tol_rad=1e-3), (stamp, got, expected)


def test_current_pose_extrapolates_along_the_twist() -> None:
    tracker = PoseTrack(max_extrapolation_s=0.3)
    _feed(tracker, 1.0)
    got = tracker.current_pose(1.1, ODOM_MAX_AGE_S)
    expected = MAP_TO_ODOM.compose(_turning(1.1))
    assert got is not None and _close(got, expected, tol_m=1e-6, tol_rad=1e-6)
    # Extrapolation is capped: a second later it has not run away.
    capped = tracker.current_pose(1.25, ODOM_MAX_AGE_S)
    assert capped is not None and _close(capped, MAP_TO_ODOM.compose(_turning(1.25)), tol_m=1e-6)
    assert tracker.twist(1.1, ODOM_MAX_AGE_S) == pytest.approx((0.4, 1.2))


def test_a_map_pose_arriving_late_pairs_with_the_odometry_it_was_taken_with() -> None:
    tracker = PoseTrack()
    _feed(tracker, 1.0)
    # The pose service is two odometry samples behind: the pose of t=0.96 arrives after t=1.0's odometry.
    tracker.add_pose(1.0, MAP_TO_ODOM.compose(_turning(0.96)))
    got = tracker.pose_now_at(1.0)
    assert got is not None and _close(got, MAP_TO_ODOM.compose(_turning(1.0)), tol_m=1e-6, tol_rad=1e-6)


def test_without_odometry_the_last_map_pose_is_used_as_is() -> None:
    tracker = PoseTrack()
    assert tracker.current_pose(0.0, ODOM_MAX_AGE_S) is None and tracker.pose_now_at(0.0) is None
    assert tracker.pose_age_s(3.0) == math.inf
    tracker.add_pose(2.0, Pose2D(1.0, 2.0, 0.5))
    assert tracker.current_pose(2.2, ODOM_MAX_AGE_S) == Pose2D(1.0, 2.0, 0.5)
    assert tracker.pose_now_at(2.1) == Pose2D(1.0, 2.0, 0.5)  # held a while
    assert tracker.pose_now_at(1.0) is None  # a reading from long before the only pose has no place
    assert tracker.twist(2.2, ODOM_MAX_AGE_S) is None
    assert tracker.pose_age_s(2.25) == pytest.approx(0.25)


def test_stale_odometry_stops_extrapolation_and_a_clock_reset_clears_history() -> None:
    tracker = PoseTrack()
    _feed(tracker, 2.0)
    last_map = MAP_TO_ODOM.compose(_turning(2.0))
    assert (
        tracker.current_pose(3.0, ODOM_MAX_AGE_S) == last_map and tracker.twist(3.0, ODOM_MAX_AGE_S) is None
    )
    # A sample older than the newest (out of order) is dropped; a jump back by over a second is a reset.
    tracker.add_odom(OdometrySample(1.5, Pose2D(), 0.0, 0.0), received_s=3.0)
    assert _close(tracker.pose_now_at(1.5), MAP_TO_ODOM.compose(_turning(1.5)))  # type: ignore[arg-type]
    tracker.add_odom(OdometrySample(0.02, Pose2D(), 0.0, 0.0), received_s=0.02)
    assert tracker.current_pose(0.02, ODOM_MAX_AGE_S) is None


def test_fresh_odometry_carries_the_map_pose_while_the_localiser_is_late() -> None:
    tracker = PoseTrack()
    assert not tracker.carried_by_odometry(0.0, ODOM_MAX_AGE_S)
    _feed(tracker, 1.0)
    assert tracker.carried_by_odometry(1.0, ODOM_MAX_AGE_S)
    for i in range(51, 101):  # another second of odometry, no map pose
        t = i / 50
        tracker.add_odom(OdometrySample(t, _turning(t), 0.4, 1.2), received_s=t)
    assert tracker.pose_age_s(2.0) == pytest.approx(1.0)
    assert tracker.carried_by_odometry(2.0, ODOM_MAX_AGE_S)
    pose = tracker.current_pose(2.0, ODOM_MAX_AGE_S)
    assert pose is not None and _close(pose, MAP_TO_ODOM.compose(_turning(2.0)), 1e-6, 1e-6)
    assert not tracker.carried_by_odometry(2.6, ODOM_MAX_AGE_S)  # the odometry has gone quiet too


def test_odometry_that_jumps_waits_for_localisation_to_catch_up() -> None:
    """A teleport restarts odometry: the old map -> odom would place the robot where it is not."""
    tracker = PoseTrack()
    _feed(tracker, 1.0)
    assert tracker.carried_by_odometry(1.0, ODOM_MAX_AGE_S)
    tracker.add_odom(OdometrySample(1.02, Pose2D(), 0.0, 0.0), received_s=1.02)  # restarted at the origin
    assert tracker.current_pose(1.02, ODOM_MAX_AGE_S) is None and not tracker.carried_by_odometry(
        1.02, ODOM_MAX_AGE_S
    )
    tracker.add_pose(1.05, MAP_TO_ODOM.compose(_turning(1.0)))  # from before, arriving late
    assert tracker.current_pose(1.05, ODOM_MAX_AGE_S) is None
    placed = Pose2D(-2.0, 3.0, 1.0)
    tracker.add_odom(OdometrySample(2.1, Pose2D(), 0.0, 0.0), received_s=2.1)
    tracker.add_pose(2.1, placed)
    tracker.add_odom(OdometrySample(2.12, Pose2D(), 0.0, 0.0), received_s=2.12)
    pose = tracker.current_pose(2.12, ODOM_MAX_AGE_S)
    assert pose is not None and _close(pose, placed)
    # A reading taken before the teleport has no place now: it was taken where the robot was.
    assert tracker.pose_now_at(1.0) is None
    at_restart = tracker.pose_now_at(1.02)
    assert at_restart is not None and _close(at_restart, placed)


def test_a_snapshot_keeps_the_correction_it_was_taken_with() -> None:
    """The planner places one costmap update's scan and echoes with one snapshot: a robot put down
    elsewhere whose odometry restarts where it stood before (at the odom origin, standing) is moved only
    by localisation, and that may arrive between placing the scan and placing the echoes."""
    here, there = Pose2D(-2.53, 4.52, -2.57), Pose2D(2.53, 4.52, -0.57)
    tracker = PoseTrack()
    for i in range(11):
        tracker.add_odom(OdometrySample(i / 10, Pose2D(), 0.0, 0.0), received_s=i / 10)
        tracker.add_pose(i / 10, here)
    snapshot = tracker.snapshot()
    for i in range(11, 16):
        tracker.add_odom(OdometrySample(i / 10, Pose2D(), 0.0, 0.0), received_s=i / 10)
        tracker.add_pose(i / 10, there)
    old, new = snapshot.pose_now_at(1.0), tracker.pose_now_at(1.0)
    assert old is not None and _close(old, here), old
    assert new is not None and _close(new, there), new
    assert snapshot.map_to_odom is not None and _close(snapshot.map_to_odom, here)
