"""The robot pose track, the dock tracker, and the obstacle checks against the simulator's own sensors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from services.docking.approach import dock_frame_error, graceful_staging_pose, offset_along
from services.docking.dock_tracker import DockTracker
from services.docking.safety import (
    LidarReturns,
    ObstacleParams,
    expected_sonar_range,
    in_corridor,
    lidar_blocked,
    scan_points,
    sonar_blocked,
)
from services.simulator.sensors import LidarParams, UltrasonicParams, lidar_scan, ultrasonic_range
from shared.geometry import Pose2D
from shared.models.raycast import SegmentSet
from shared.pose_tracking import OdometrySample, PoseTrack
from shared.structs import plain
from shared.world import World, load_world, parse_world
from tests.support.processes import REPO_ROOT
from tests.unit.docking.harness import SEED_DOCK


def close(a: Pose2D | None, b: Pose2D, tol: float = 1e-9) -> bool:
    assert a is not None
    return a.distance_to(b) < tol and abs(math.remainder(a.yaw - b.yaw, 2 * math.pi)) < tol


def arc(start: Pose2D, v: float, w: float, t: float) -> Pose2D:
    if w == 0.0:
        return start.compose(Pose2D(v * t, 0.0, 0.0))
    return start.compose(Pose2D(v / w * math.sin(w * t), v / w * (1 - math.cos(w * t)), w * t))


# --- robot pose track -------------------------------------------------------------------------------


def test_without_odometry_samples_are_interpolated_and_held_a_while() -> None:
    track = PoseTrack()
    track.add_pose(1.0, Pose2D(0.0, 0.0, 0.0))
    track.add_pose(1.1, Pose2D(0.1, 0.0, 0.2))
    assert close(track.pose_at(1.05), Pose2D(0.05, 0.0, 0.1))
    assert close(track.pose_at(1.4), Pose2D(0.1, 0.0, 0.2))
    assert track.pose_at(2.0) is None  # held at most MAX_HOLD_S
    assert track.pose_fresh(1.5, 0.5) and not track.pose_fresh(1.7, 0.5)
    assert track.latest() == (1.1, Pose2D(0.1, 0.0, 0.2))


def test_localisation_samples_are_carried_forward_by_odometry() -> None:
    """With a constant localisation error (in base_link) the composed pose is the believed pose, at any time."""
    error = Pose2D(0.03, -0.02, 0.02)
    start = Pose2D(-1.0, 1.53, -math.pi / 2)
    v, w = 0.3, 0.4
    track = PoseTrack()
    for i in range(0, 101):  # odometry at 50 Hz from the start pose, localisation at 10 Hz
        t = i * 0.02
        true = arc(start, v, w, t)
        odom = start.inverse().compose(true)  # odometry starts at the identity
        track.add_odom(OdometrySample(t, odom, v, w))
        if i % 5 == 0:
            track.add_pose(t, true.compose(error))
    for t in (0.55, 1.23, 1.999):
        expected = arc(start, v, w, t).compose(error)
        assert close(track.pose_at(t), expected, 1e-3), t
    stamp, latest = track.latest()  # type: ignore[misc]
    assert stamp == pytest.approx(2.0) and close(latest, arc(start, v, w, 2.0).compose(error), 1e-3)
    assert track.twist(2.0, 0.5) == (v, w)
    assert track.twist(3.0, 0.5) is None


def test_an_odometry_jump_drops_what_cannot_be_carried_across_it() -> None:
    track = PoseTrack()
    track.add_odom(OdometrySample(0.0, Pose2D(), 0.0, 0.0))
    track.add_pose(0.0, Pose2D(2.0, 2.0, 0.0))
    track.add_odom(OdometrySample(0.02, Pose2D(0.001, 0.0, 0.0), 0.05, 0.0))
    assert track.has_pose
    track.add_odom(OdometrySample(0.04, Pose2D(1.5, 0.3, 1.0), 0.0, 0.0))  # a teleport
    assert not track.has_pose and track.odom_resets == 1
    # The localiser may still report where the robot was: its poses are ignored while it settles.
    track.add_pose(0.05, Pose2D(2.0, 2.0, 0.0))
    assert not track.has_pose
    track.add_pose(0.04 + track.relocalise_settle_s + 0.01, Pose2D(5.0, 1.0, 1.0))
    assert close(track.pose_at(1.05), Pose2D(5.0, 1.0, 1.0), 1e-6)


def test_a_clock_that_jumps_back_clears_the_history() -> None:
    track = PoseTrack()
    track.add_pose(100.0, Pose2D(1.0, 0.0, 0.0))
    track.add_pose(2.0, Pose2D(3.0, 0.0, 0.0))
    assert track.latest() == (2.0, Pose2D(3.0, 0.0, 0.0))
    assert track.pose_at(100.0) is None


# --- dock tracker -----------------------------------------------------------------------------------


def test_the_localisation_error_cancels_in_the_robot_to_dock_geometry() -> None:
    error = Pose2D(0.03, 0.06, 0.03)
    tracker = DockTracker()
    tracker.expect(SEED_DOCK)
    true_robot = graceful_staging_pose(SEED_DOCK).compose(Pose2D(0.0, 0.05, 0.1))
    believed = true_robot.compose(error)
    for i in range(10):
        assert tracker.add(SEED_DOCK.relative_to(true_robot), believed, 0.1 * i)
    estimate = tracker.estimate()
    assert estimate is not None and estimate.detections == 10
    assert close(believed.relative_to(estimate.pose), true_robot.relative_to(SEED_DOCK), 1e-9)
    assert estimate.pose.distance_to(SEED_DOCK) > 0.05  # in the believed map, not the true one


def test_detections_of_something_else_or_from_before_are_ignored() -> None:
    tracker = DockTracker(max_offset_m=0.5)
    robot = graceful_staging_pose(SEED_DOCK)
    assert not tracker.add(SEED_DOCK.relative_to(robot), robot, 0.0)  # nothing expected yet
    tracker.expect(SEED_DOCK)
    other_dock = offset_along(SEED_DOCK, 0.0, 1.0)
    assert not tracker.add(other_dock.relative_to(robot), robot, 0.1)
    assert tracker.ignored == 1 and tracker.estimate() is None
    tracker.reset(accept_from_s=5.0)
    assert not tracker.add(SEED_DOCK.relative_to(robot), robot, 4.9)
    assert tracker.add(SEED_DOCK.relative_to(robot), robot, 5.0)
    tracker.expect(Pose2D(2.0, 0.83, -math.pi / 2))  # another dock: start afresh
    assert tracker.estimate() is None


# --- obstacle checks on the simulator's sensors --------------------------------------------------------


@pytest.fixture(scope="module")
def seed_room() -> World:
    return load_world(REPO_ROOT / "deploy/worlds/seed_room.yaml")


def sense(world: World, pose: Pose2D, extra_boxes: list[dict] | None = None) -> tuple[np.ndarray, float]:  # type: ignore[type-arg]
    if extra_boxes:
        world = parse_world(plain(world) | {"boxes": [*plain(world)["boxes"], *extra_boxes]})
    segments = SegmentSet(world.opaque_segments())
    rng = np.random.default_rng(0)
    lidar = LidarParams(noise_m=0.0)
    scan = lidar_scan(pose, segments, lidar, rng)
    points = LidarReturns(scan.ranges_m, scan.angle_min_rad, scan.angle_increment_rad, lidar.mount).points
    sonar = ultrasonic_range(pose, segments, UltrasonicParams(noise_m=0.0), rng)
    return points, sonar


def test_a_scan_s_points_are_worked_out_once_when_first_asked_for() -> None:
    ranges = np.array([1.0, np.inf, 2.0, np.nan, 0.5])
    mount = Pose2D(0.1, 0.0, 0.2)
    returns = LidarReturns(ranges, -0.5, 0.25, mount)
    first = returns.points
    assert first.shape == (3, 2)  # the finite returns only
    np.testing.assert_allclose(first, scan_points(ranges, -0.5, 0.25, mount))
    assert returns.points is first
    given = np.array([[0.3, 0.1]])
    np.testing.assert_array_equal(LidarReturns.of_points(given).points, given)


APPROACH = [
    offset_along(SEED_DOCK, -back, lateral, yaw)
    for back in (0.7, 0.4, 0.2, 0.1, 0.05, 0.0)
    for lateral in (-0.03, 0.0, 0.03)
    for yaw in (-0.08, 0.0, 0.08)
]


@pytest.mark.parametrize("pose", APPROACH, ids=lambda p: f"{p.x:.2f},{p.y:.2f},{p.yaw:.2f}")
def test_the_dock_itself_never_blocks_the_approach(seed_room: World, pose: Pose2D) -> None:
    points, sonar = sense(seed_room, pose)
    dock_in_base = SEED_DOCK.relative_to(pose)
    params = ObstacleParams()
    assert not lidar_blocked(points, True, dock_in_base, params)
    assert not sonar_blocked(sonar, dock_in_base, params), (sonar, expected_sonar_range(dock_in_base, params))
    if -dock_frame_error(pose, SEED_DOCK).along_m < params.stop_distance_m - 0.02:
        assert lidar_blocked(
            points, True, None, params
        )  # the dock is in the way: only the excuse lets it pass


def test_a_pillar_in_the_approach_blocks_it(seed_room: World) -> None:
    pose = graceful_staging_pose(SEED_DOCK)
    points, sonar = sense(seed_room, pose, [{"pose": [-0.95, 1.15, 0.0], "size": [0.1, 0.1]}])
    dock_in_base = SEED_DOCK.relative_to(pose)
    params = ObstacleParams()
    assert lidar_blocked(points, True, dock_in_base, params)
    assert sonar_blocked(sonar, dock_in_base, params)
    assert not lidar_blocked(points, False, dock_in_base, params)  # nothing behind


def test_backing_off_looks_behind(seed_room: World) -> None:
    params = ObstacleParams()
    facing_away, _ = sense(seed_room, Pose2D(-1.0, 0.9, math.pi / 2))  # the dock's body right behind
    assert lidar_blocked(facing_away, False, None, params)
    docked, _ = sense(seed_room, SEED_DOCK)
    assert not lidar_blocked(docked, False, None, params)  # backing off the dock: open floor behind
    corridor = in_corridor(np.array([[0.3, 0.0], [0.3, 0.3], [-0.3, 0.0], [0.6, 0.0]]), True, params)
    assert corridor.tolist() == [True, False, False, False]


def test_sonar_rules() -> None:
    params = ObstacleParams(stop_distance_m=0.3, sonar_dock_tolerance_m=0.08)
    ahead = Pose2D(0.5, 0.0, 0.0)  # the dock pose 0.5 m ahead: its plate 0.5 m from the front
    assert expected_sonar_range(ahead, params) == pytest.approx(0.5)
    assert not sonar_blocked(math.inf, None, params)
    assert not sonar_blocked(0.35, None, params)
    assert sonar_blocked(0.25, None, params)
    assert sonar_blocked(0.25, ahead, params)  # well short of the plate
    near = Pose2D(0.2, 0.0, 0.0)
    assert not sonar_blocked(0.2, near, params) and not sonar_blocked(0.13, near, params)
    assert sonar_blocked(0.1, near, params)
    past = Pose2D(-0.01, 0.0, 0.0)  # the robot believes its front is past the plate
    assert expected_sonar_range(past, params) == 0.0 and not sonar_blocked(0.02, past, params)
    aside = Pose2D(0.5, 2.0, 0.0)  # the dock far to the left: not in the cone
    assert expected_sonar_range(aside, params) == math.inf and sonar_blocked(0.2, aside, params)


def test_a_late_localisation_sample_pairs_with_the_odometry_it_was_made_from() -> None:
    """Poses arriving late, or before the odometry of their time, still give the right map -> odom."""
    correction = Pose2D(0.5, -0.2, 0.1)
    start = Pose2D(0.0, 0.0, 0.3)
    v, w = 0.4, 0.6
    track = PoseTrack()
    for i in range(0, 60):
        t = i * 0.02
        track.add_odom(OdometrySample(t, arc(start, v, w, t), v, w))
        if i % 5 == 0 and i >= 10:
            late_by = 0.1 if i % 10 == 0 else 0.0  # computed 0.1 s before it arrives, or on time
            track.add_pose(t, correction.compose(arc(start, v, w, t - late_by)))
    assert track.map_to_odom is not None and close(track.map_to_odom, correction, 1e-9)
    # A sample computed from odometry that has not arrived yet is paired once that odometry comes.
    t_next = 60 * 0.02
    track.add_pose(t_next, correction.compose(arc(start, v, w, t_next)))
    track.add_odom(OdometrySample(t_next, arc(start, v, w, t_next), v, w))
    assert close(track.map_to_odom, correction, 1e-9)
    stamp, latest = track.latest()  # type: ignore[misc]
    assert stamp == pytest.approx(t_next) and close(
        latest, correction.compose(arc(start, v, w, t_next)), 1e-9
    )
    assert close(track.pose_now_at(0.9), correction.compose(arc(start, v, w, 0.9)), 1e-9)


def test_odometry_carries_a_late_localisation_sample_forward() -> None:
    track = PoseTrack()
    track.add_odom(OdometrySample(0.0, Pose2D(), 0.0, 0.0))
    track.add_pose(0.0, Pose2D(1.0, 1.0, 0.0))
    for i in range(1, 51):
        track.add_odom(OdometrySample(0.02 * i, Pose2D(0.01 * i, 0.0, 0.0), 0.5, 0.0))
    assert not track.pose_fresh(1.0, 0.5)  # localisation alone is a second old ...
    assert track.pose_fresh(1.0, 0.5, carried_age_s=2.0)  # ... but fresh odometry carries it
    assert not track.pose_fresh(3.5, 0.5, carried_age_s=2.0)  # and not for ever
    assert not track.pose_fresh(1.7, 0.5, carried_age_s=2.0)  # nor when the odometry is stale too


def test_the_detected_dock_moves_with_the_localisers_correction() -> None:
    """A correction that moves the robot's map pose moves the dock estimate with it: the geometry between
    them stays what odometry says (the dock is tracked in the odometry frame, in effect)."""
    tracker = DockTracker()
    tracker.expect(SEED_DOCK)
    robot = graceful_staging_pose(SEED_DOCK)
    for i in range(5):
        tracker.add(SEED_DOCK.relative_to(robot), robot, 0.1 * i)
    before = tracker.estimate()
    assert before is not None
    correction = Pose2D(0.02, -0.01, 0.015)  # new map -> odom = correction * old
    tracker.shift(correction)
    moved_robot = correction.compose(robot)
    after = tracker.estimate()
    assert after is not None and after.detections == before.detections
    assert close(moved_robot.relative_to(after.pose), robot.relative_to(before.pose), 1e-9)
