"""Lidar, ultrasonic ranger and dock camera: what each sees, and what it does not."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from services.simulator.physics import Robot, SimParams
from services.simulator.sensors import LidarParams, UltrasonicParams, lidar_scan
from shared.geometry import Pose2D
from shared.models.raycast import SegmentSet, cast_rays
from shared.world import World, load_world

FORWARD_BEAM = 180  # angle_min = -pi, 1 degree apart: beam 180 looks straight ahead
LEFT_BEAM = 270


def test_cast_rays_against_known_geometry() -> None:
    segments = SegmentSet([((1.0, -1.0), (1.0, 1.0)), ((3.0, -1.0), (3.0, 1.0))])
    ranges = cast_rays((0.0, 0.0), np.array([0.0, math.pi / 4, math.pi, math.pi / 2]), segments)
    assert ranges[0] == pytest.approx(1.0)  # the nearer of two walls
    assert ranges[1] == pytest.approx(math.sqrt(2.0))  # hits the end point
    assert np.isinf(ranges[2]) and np.isinf(ranges[3])  # behind, and parallel


def test_lidar_sees_walls_but_not_glass_and_sonar_sees_glass(quiet: SimParams, worlds_dir: Path) -> None:
    sim = Robot(load_world(worlds_dir / "glass_room.yaml"), params=quiet)
    behind_glass = Pose2D(0.0, 3.5, -math.pi / 2)  # glass 0.9 m ahead, south wall beyond it
    scan = sim.lidar_scan(behind_glass)
    assert scan.ranges_m[FORWARD_BEAM] == pytest.approx(3.5 - 0.10 - 0.43)  # through the glass
    assert sim.ultrasonic_range(behind_glass) == pytest.approx(3.5 - 0.20 - 2.6)  # bounces off it
    behind_wall = Pose2D(-2.5, 3.5, -math.pi / 2)  # the opaque part of the partition ahead
    assert sim.lidar_scan(behind_wall).ranges_m[FORWARD_BEAM] == pytest.approx(3.5 - 0.10 - 2.6)
    assert sim.ultrasonic_range(behind_wall) == pytest.approx(3.5 - 0.20 - 2.6)


def test_lidar_frame_and_noise(worlds_dir: Path) -> None:
    sim = Robot(load_world(worlds_dir / "seed_room.yaml"))  # default noise, sigma 1 cm
    pose = Pose2D(0.0, 2.0, 0.0)
    scan = sim.lidar_scan(pose)
    assert scan.ranges_m.shape == (360,)
    assert scan.angle_min_rad == pytest.approx(-math.pi) and scan.angle_increment_rad == pytest.approx(
        math.pi / 180
    )
    assert scan.ranges_m[FORWARD_BEAM] == pytest.approx(3.0 - 0.10, abs=0.05)  # east wall
    assert scan.ranges_m[LEFT_BEAM] == pytest.approx(5.0 - 2.0, abs=0.05)  # north wall, on the left
    errors = [sim.lidar_scan(pose).ranges_m[LEFT_BEAM] - 3.0 for _ in range(200)]
    assert 0.005 < float(np.std(errors)) < 0.015


def test_lidar_out_of_range_reads_inf(open_world: Callable[..., World]) -> None:
    rng = np.random.default_rng(1)
    far = SegmentSet(open_world(bounds=[-20.0, -20.0, 20.0, 20.0]).opaque_segments())
    assert np.isinf(lidar_scan(Pose2D(), far, LidarParams(), rng).ranges_m).all()
    too_close = SegmentSet([((0.15, -1.0), (0.15, 1.0))])  # 5 cm ahead of the lidar, under range_min
    ranges = lidar_scan(Pose2D(), too_close, LidarParams(noise_m=0.0), rng).ranges_m
    assert np.isinf(ranges[FORWARD_BEAM])
    assert ranges[FORWARD_BEAM + 70] == pytest.approx(0.05 / math.cos(math.radians(70)))


def test_sonar_reads_nearest_in_its_cone_and_inf_beyond_range(
    quiet: SimParams, open_world: Callable[..., World]
) -> None:
    # A post 1 m ahead of the ranger and off to the left, its lower end inside the cone (edge at 0.25 rad).
    post = [[[1.2, 0.2], [1.2, 0.4]]]
    sim = Robot(open_world(walls=post), params=quiet)
    assert sim.ultrasonic_range() == pytest.approx(math.hypot(1.0, 0.2))
    sim_narrow = Robot(
        open_world(walls=post), params=SimParams(ultrasonic=UltrasonicParams(field_of_view_rad=0.3))
    )
    assert math.isinf(sim_narrow.ultrasonic_range())
    pressed = Robot(open_world(walls=[[[1.0, -1.0], [1.0, 1.0]]]), params=quiet)
    pressed.teleport(Pose2D(0.795, 0.0, 0.0))  # 5 mm from the wall, under the 2 cm minimum
    assert pressed.ultrasonic_range() == pytest.approx(0.02)
    assert math.isinf(sim.ultrasonic_range(Pose2D(0.0, 0.0, math.pi)))  # 4.8 m of open floor behind


def test_sensor_calls_are_fast(worlds_dir: Path) -> None:
    sim = Robot(load_world(worlds_dir / "seed_room.yaml"))
    batches = []
    for _ in range(5):
        started = time.perf_counter()
        for _ in range(20):
            sim.lidar_scan()
        batches.append((time.perf_counter() - started) / 20)
    assert min(batches) < 0.001  # 360 rays; measured ~0.15 ms


# ------------------------------------------------------------------------------------------- dock camera
# dock_world: dock pose at the origin facing +x; marker at (0.2, 0) facing -x; camera 0.15 m ahead of base.


def test_dock_seen_ahead_reports_the_dock_pose_in_base_link(
    quiet: SimParams, dock_world: Callable[..., World]
) -> None:
    sim = Robot(dock_world(), params=quiet)
    robot = Pose2D(-1.0, 0.3, -0.2)
    detection = sim.detect_dock(robot)
    assert detection is not None and detection.dock_id == "home"
    expected = Pose2D(0.0, 0.0, 0.0).relative_to(robot)
    assert detection.dock_pose_in_base.as_tuple() == pytest.approx(expected.as_tuple())
    docked = sim.detect_dock(Pose2D(-0.5, 0.0, 0.0))
    assert docked is not None and docked.dock_pose_in_base.as_tuple() == pytest.approx((0.5, 0.0, 0.0))


def test_detection_noise_is_small_and_unbiased(dock_world: Callable[..., World]) -> None:
    sim = Robot(dock_world())
    xs = []
    for _ in range(300):
        detection = sim.detect_dock(Pose2D(-1.0, 0.0, 0.0))
        assert detection is not None
        xs.append(detection.dock_pose_in_base.x)
    assert float(np.mean(xs)) == pytest.approx(1.0, abs=0.001)
    assert 0.002 < float(np.std(xs)) < 0.004


@pytest.mark.parametrize(
    "robot",
    [
        pytest.param(Pose2D(-1.0, 0.0, math.pi / 2), id="out-of-fov"),
        pytest.param(Pose2D(-1.0, 0.0, math.pi), id="looking-away"),
        pytest.param(Pose2D(1.2, 0.0, math.pi), id="behind-the-dock"),
        pytest.param(Pose2D(-3.0, 0.0, 0.0), id="too-far"),
    ],
)
def test_dock_not_seen(robot: Pose2D, quiet: SimParams, dock_world: Callable[..., World]) -> None:
    sim = Robot(dock_world(), params=quiet)
    assert sim.detect_dock(robot) is None
    assert sim.detect_docks(robot) == []


def _camera_looking_at_marker(view_angle_rad: float, distance_m: float) -> Pose2D:
    """A robot pose whose camera sits ``view_angle_rad`` off the marker's normal and looks at the marker."""
    marker_x, marker_y = 0.2, 0.0
    cam_x = marker_x + distance_m * math.cos(math.pi - view_angle_rad)
    cam_y = marker_y + distance_m * math.sin(math.pi - view_angle_rad)
    yaw = math.atan2(marker_y - cam_y, marker_x - cam_x)
    return Pose2D(cam_x - 0.15 * math.cos(yaw), cam_y - 0.15 * math.sin(yaw), yaw)


def test_marker_readable_only_below_70_degrees_off_its_normal(
    quiet: SimParams, dock_world: Callable[..., World]
) -> None:
    sim = Robot(dock_world(), params=quiet)
    assert sim.detect_dock(_camera_looking_at_marker(math.radians(60), 1.0)) is not None
    assert sim.detect_dock(_camera_looking_at_marker(math.radians(75), 1.0)) is None


def test_box_hides_the_marker_but_glass_does_not(quiet: SimParams, dock_world: Callable[..., World]) -> None:
    robot = Pose2D(-1.5, 0.0, 0.0)
    boxed = Robot(dock_world(boxes=[{"pose": [-0.6, 0.0, 0.0], "size": [0.1, 0.3]}]), params=quiet)
    assert boxed.detect_dock(robot) is None
    glazed = Robot(dock_world(glass=[[[-0.6, -1.0], [-0.6, 1.0]]]), params=quiet)
    assert glazed.detect_dock(robot) is not None
    assert math.isfinite(glazed.ultrasonic_range(robot)) and glazed.ultrasonic_range(robot) < 0.8
