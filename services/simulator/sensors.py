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
from typing import Annotated

import numpy as np
from msgspec import Meta

from shared.geometry import Pose2D, wrap_angle
from shared.models.component import ComponentParams
from shared.models.raycast import SegmentSet, cast_rays, nearest_in_cone, segment_blocked
from shared.world import DOCK_GEOMETRY, Dock

#: The forward camera's mount ahead of base_link: the rendered camera and the fiducial detector are one camera.
CAMERA_MOUNT_X_M = 0.15


def _check_range(owner: ComponentParams) -> None:
    low, high = owner.range_min_m, owner.range_max_m  # type: ignore[attr-defined]
    if high <= low:
        raise ValueError(f"range_max_m: {high} must exceed range_min_m {low} ({type(owner).__name__})")


@functools.lru_cache(maxsize=8)
def _beam_angles(num_rays: int) -> np.ndarray:
    angles = -math.pi + (2.0 * math.pi / num_rays) * np.arange(num_rays)
    angles.flags.writeable = False
    return angles


class LidarParams(ComponentParams, frozen=True):
    """A 360-degree planar lidar on lidar_link (``mount_x_m`` ahead of base_link, same heading)."""

    rate_hz: Annotated[float, Meta(gt=0, description="scans per second (sim time)")] = 10.0
    num_rays: Annotated[int, Meta(ge=1)] = 360
    range_min_m: Annotated[float, Meta(gt=0)] = 0.12
    range_max_m: Annotated[float, Meta(gt=0)] = 8.0
    noise_m: Annotated[float, Meta(ge=0, description="range noise (sigma)")] = 0.01
    mount_x_m: float = 0.10
    mount_y_m: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_range(self)

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


class UltrasonicParams(ComponentParams, frozen=True):
    """A single ultrasonic ranger on ultrasonic_link, at the front centre, facing forward."""

    rate_hz: Annotated[float, Meta(gt=0, description="pings per second (sim time)")] = 20.0
    field_of_view_rad: Annotated[float, Meta(gt=0, lt=math.pi)] = 0.5
    range_min_m: Annotated[float, Meta(gt=0)] = 0.02
    range_max_m: Annotated[float, Meta(gt=0)] = 3.0
    noise_m: Annotated[float, Meta(ge=0, description="range noise (sigma)")] = 0.005
    mount_x_m: float = 0.20

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_range(self)

    @property
    def mount(self) -> Pose2D:
        """ultrasonic_link in base_link."""
        return Pose2D(self.mount_x_m, 0.0, 0.0)


class FiducialCameraParams(ComponentParams, frozen=True):
    """The forward camera that finds the dock's marker (mounted ``mount_x_m`` ahead of base_link)."""

    mount_x_m: float = CAMERA_MOUNT_X_M
    horizontal_fov_rad: Annotated[float, Meta(gt=0, lt=math.pi)] = 1.2
    range_min_m: Annotated[float, Meta(gt=0)] = 0.1
    range_max_m: Annotated[float, Meta(gt=0)] = 2.5
    #: The marker is readable while the angle between its normal and the line of sight is below this.
    max_view_angle_rad: Annotated[float, Meta(gt=0)] = math.radians(70.0)
    position_sigma_m: Annotated[float, Meta(ge=0)] = 0.003
    yaw_sigma_rad: Annotated[float, Meta(ge=0)] = 0.01

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
    if params.noise_m > 0.0:
        ranges = ranges + rng.normal(0.0, params.noise_m, ranges.shape)
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
    if params.noise_m > 0.0:
        nearest += float(rng.normal(0.0, params.noise_m))
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
