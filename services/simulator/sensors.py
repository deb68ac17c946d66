"""Simulated sensors of the robot: 2-D lidar, front ultrasonic ranger, fiducial (ARTag) dock camera.

Pure functions of the robot's true pose, the world's segments and a random generator. What each sensor
sees is the point of the glass room: the lidar's light passes through glass, the ultrasonic ping bounces
off it, and a camera sees a marker through it.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from services.simulator.raycast import SegmentSet, cast_rays, nearest_in_cone, segment_blocked
from shared.geometry import Pose2D, wrap_angle
from shared.world import DOCK_GEOMETRY, Dock


def _check_positive(owner: object, *names: str) -> None:
    for name in names:
        value = getattr(owner, name)
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{type(owner).__name__}.{name} must be a positive number, got {value!r}")


def _check_non_negative(owner: object, *names: str) -> None:
    for name in names:
        value = getattr(owner, name)
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{type(owner).__name__}.{name} must be >= 0, got {value!r}")


@functools.lru_cache(maxsize=8)
def _beam_angles(num_rays: int) -> np.ndarray:
    angles = -math.pi + (2.0 * math.pi / num_rays) * np.arange(num_rays)
    angles.flags.writeable = False
    return angles


@dataclass(frozen=True, slots=True)
class LidarParams:
    """A 360-degree planar lidar on lidar_link (``mount_x_m`` ahead of base_link, same heading)."""

    num_rays: int = 360
    range_min_m: float = 0.12
    range_max_m: float = 8.0
    noise_sigma_m: float = 0.01
    mount_x_m: float = 0.10
    mount_y_m: float = 0.0

    def __post_init__(self) -> None:
        if self.num_rays < 1:
            raise ValueError(f"LidarParams.num_rays must be >= 1, got {self.num_rays}")
        _check_positive(self, "range_min_m", "range_max_m")
        _check_non_negative(self, "noise_sigma_m")
        if self.range_max_m <= self.range_min_m:
            raise ValueError(
                f"LidarParams: range_max_m {self.range_max_m} must exceed range_min_m {self.range_min_m}"
            )

    @property
    def angle_min_rad(self) -> float:
        return -math.pi

    @property
    def angle_increment_rad(self) -> float:
        return 2.0 * math.pi / self.num_rays

    @property
    def angle_max_rad(self) -> float:
        return self.angle_min_rad + (self.num_rays - 1) * self.angle_increment_rad

    @property
    def mount(self) -> Pose2D:
        """lidar_link in base_link."""
        return Pose2D(self.mount_x_m, self.mount_y_m, 0.0)

    def beam_angles_rad(self) -> np.ndarray:
        """Beam angles in lidar_link, ``angle_min + i * angle_increment`` as in sensor_msgs/LaserScan."""
        return _beam_angles(self.num_rays)


@dataclass(frozen=True, slots=True)
class LidarScan:
    """One revolution, in lidar_link; field names follow sensor_msgs/LaserScan."""

    angle_min_rad: float
    angle_increment_rad: float
    range_min_m: float
    range_max_m: float
    ranges_m: np.ndarray


@dataclass(frozen=True, slots=True)
class UltrasonicParams:
    """A single ultrasonic ranger on ultrasonic_link, at the front centre, facing forward."""

    field_of_view_rad: float = 0.5
    range_min_m: float = 0.02
    range_max_m: float = 3.0
    noise_sigma_m: float = 0.005
    mount_x_m: float = 0.20

    def __post_init__(self) -> None:
        _check_positive(self, "field_of_view_rad", "range_min_m", "range_max_m")
        _check_non_negative(self, "noise_sigma_m")
        if self.field_of_view_rad >= math.pi:
            raise ValueError(f"UltrasonicParams.field_of_view_rad must be below pi, got {self.field_of_view_rad}")
        if self.range_max_m <= self.range_min_m:
            raise ValueError(
                f"UltrasonicParams: range_max_m {self.range_max_m} must exceed range_min_m {self.range_min_m}"
            )

    @property
    def mount(self) -> Pose2D:
        """ultrasonic_link in base_link."""
        return Pose2D(self.mount_x_m, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class FiducialCameraParams:
    """The forward camera that finds the dock's marker (mounted ``mount_x_m`` ahead of base_link)."""

    mount_x_m: float = 0.15
    horizontal_fov_rad: float = 1.2
    range_min_m: float = 0.1
    range_max_m: float = 2.5
    #: The marker is readable while the angle between its normal and the line of sight is below this.
    max_view_angle_rad: float = math.radians(70.0)
    position_sigma_m: float = 0.003
    yaw_sigma_rad: float = 0.01

    def __post_init__(self) -> None:
        _check_positive(self, "horizontal_fov_rad", "range_min_m", "range_max_m", "max_view_angle_rad")
        _check_non_negative(self, "position_sigma_m", "yaw_sigma_rad")

    @property
    def mount(self) -> Pose2D:
        return Pose2D(self.mount_x_m, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class DockDetection:
    """A dock found by its marker.

    ``dock_pose_in_base`` is the measured pose of the *dock* (the base_link pose at which the robot is
    docked), expressed in the robot's base_link frame, noise included; the service publishes it as the
    detected dock pose. Zero means the robot is docked. ``marker_range_m`` and ``marker_bearing_rad`` are
    the true camera-to-marker geometry, for diagnostics.
    """

    dock_id: str
    dock_pose_in_base: Pose2D
    marker_range_m: float
    marker_bearing_rad: float


def lidar_scan(
    robot_pose: Pose2D, segments: SegmentSet, params: LidarParams, rng: np.random.Generator
) -> LidarScan:
    """A scan of ``segments`` from the lidar on the robot at ``robot_pose``.

    Readings outside ``[range_min_m, range_max_m]`` (nothing in range, or closer than the lidar can
    measure) are ``inf``; readings in range carry Gaussian noise.
    """
    sensor = robot_pose.compose(params.mount)
    ranges = cast_rays((sensor.x, sensor.y), sensor.yaw + params.beam_angles_rad(), segments)
    in_range = (ranges >= params.range_min_m) & (ranges <= params.range_max_m)
    if params.noise_sigma_m > 0.0:
        ranges = ranges + rng.normal(0.0, params.noise_sigma_m, ranges.shape)
    ranges = np.where(in_range, ranges, np.inf)
    return LidarScan(
        angle_min_rad=params.angle_min_rad,
        angle_increment_rad=params.angle_increment_rad,
        range_min_m=params.range_min_m,
        range_max_m=params.range_max_m,
        ranges_m=ranges,
    )


def ultrasonic_range(
    robot_pose: Pose2D, segments: SegmentSet, params: UltrasonicParams, rng: np.random.Generator
) -> float:
    """The ranger's reading: the nearest echo across its cone, with Gaussian noise.

    ``inf`` when nothing lies within ``range_max_m`` (sensor_msgs/Range convention). An object closer than
    ``range_min_m`` reads ``range_min_m``: the ranger reports "as close as I can tell", never "clear".
    """
    sensor = robot_pose.compose(params.mount)
    nearest = nearest_in_cone((sensor.x, sensor.y), sensor.yaw, 0.5 * params.field_of_view_rad, segments)
    if nearest > params.range_max_m:
        return math.inf
    if params.noise_sigma_m > 0.0:
        nearest += float(rng.normal(0.0, params.noise_sigma_m))
    return min(params.range_max_m, max(params.range_min_m, nearest))


def marker_view(robot_pose: Pose2D, dock: Dock, occluders: SegmentSet, params: FiducialCameraParams) -> bool:
    """Whether the camera can read ``dock``'s marker: in range, in view, facing the camera, unoccluded."""
    camera = robot_pose.compose(params.mount)
    marker = DOCK_GEOMETRY.marker_pose(dock)
    dx, dy = marker.x - camera.x, marker.y - camera.y
    distance = math.hypot(dx, dy)
    if not (params.range_min_m <= distance <= params.range_max_m):
        return False
    if abs(wrap_angle(math.atan2(dy, dx) - camera.yaw)) > 0.5 * params.horizontal_fov_rad:
        return False
    # The marker's normal (its x axis) against the direction from the marker back to the camera.
    if abs(wrap_angle(math.atan2(-dy, -dx) - marker.yaw)) >= params.max_view_angle_rad:
        return False
    return not segment_blocked((camera.x, camera.y), (marker.x, marker.y), occluders)


def detect_docks(
    robot_pose: Pose2D,
    docks: Sequence[Dock],
    occluders: SegmentSet,
    params: FiducialCameraParams,
    rng: np.random.Generator,
) -> list[DockDetection]:
    """Every dock whose marker the camera reads, nearest first (see :class:`DockDetection`)."""
    camera = robot_pose.compose(params.mount)
    found: list[DockDetection] = []
    for dock in docks:
        if not marker_view(robot_pose, dock, occluders, params):
            continue
        marker = DOCK_GEOMETRY.marker_pose(dock)
        truth = dock.pose2d.relative_to(robot_pose)
        noise_x, noise_y = (
            rng.normal(0.0, params.position_sigma_m, 2) if params.position_sigma_m > 0 else (0, 0)
        )
        noise_yaw = rng.normal(0.0, params.yaw_sigma_rad) if params.yaw_sigma_rad > 0 else 0.0
        measured = Pose2D(
            truth.x + float(noise_x), truth.y + float(noise_y), wrap_angle(truth.yaw + float(noise_yaw))
        )
        found.append(
            DockDetection(
                dock_id=dock.id,
                dock_pose_in_base=measured,
                marker_range_m=camera.distance_to(marker),
                marker_bearing_rad=wrap_angle(
                    math.atan2(marker.y - camera.y, marker.x - camera.x) - camera.yaw
                ),
            )
        )
    found.sort(key=lambda d: d.marker_range_m)
    return found
