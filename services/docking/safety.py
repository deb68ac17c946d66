"""Is something in the robot's way while it docks? Lidar and sonar checks that know where the dock is.

At the end of an approach the dock's body is right in front of the robot, so a plain "anything close
ahead" test would stop every docking. Both checks therefore ignore returns consistent with the dock:

- lidar: points in a corridor as wide as the robot (plus a margin) reaching ``stop_distance_m`` past its
  front (or rear, when backing up) count, except those in the dock region -- everything at or behind
  the plate's face within the dock's width plus ``dock_margin_m``, in the dock's frame;
- sonar (front only): the reading counts when it is within ``stop_distance_m`` and shorter, by more than
  ``sonar_dock_tolerance_m``, than the range at which the ranger's cone would meet the plate's line
  (within the dock's width plus ``dock_margin_m``); a plate expected at or behind the robot's front (a
  robot that is slightly mislocalised at the end of its approach) excuses every reading.

Points are in base_link; the dock pose is given in base_link too (``dock_pose.relative_to(robot_pose)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from shared.geometry import Pose2D
from shared.world import DOCK_GEOMETRY, ROBOT_FRONT_M, ROBOT_LENGTH_M, ROBOT_WIDTH_M


@dataclass(frozen=True, slots=True)
class ObstacleParams:
    """How far ahead the robot looks and how generously the dock is excused."""

    stop_distance_m: float = 0.3
    side_margin_m: float = 0.05
    dock_margin_m: float = 0.10
    sonar_dock_tolerance_m: float = 0.08
    #: Cone of the front ranger, and how many rays model it (the simulator's own ranger uses 7).
    sonar_fov_rad: float = 0.5
    sonar_rays: int = 7
    robot_length_m: float = ROBOT_LENGTH_M
    robot_width_m: float = ROBOT_WIDTH_M

    def __post_init__(self) -> None:
        for name in (
            "stop_distance_m",
            "side_margin_m",
            "dock_margin_m",
            "sonar_dock_tolerance_m",
            "sonar_fov_rad",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"ObstacleParams.{name} must be >= 0, got {value!r}")
        if self.sonar_rays < 1:
            raise ValueError(f"ObstacleParams.sonar_rays must be >= 1, got {self.sonar_rays}")


def scan_points(
    ranges_m: np.ndarray, angle_min_rad: float, angle_increment_rad: float, mount: Pose2D
) -> np.ndarray:
    """The finite returns of a planar scan as an ``(N, 2)`` array of points in base_link."""
    ranges = np.asarray(ranges_m, dtype=float)
    angles = angle_min_rad + angle_increment_rad * np.arange(ranges.size)
    valid = np.isfinite(ranges)
    local = np.column_stack((ranges[valid] * np.cos(angles[valid]), ranges[valid] * np.sin(angles[valid])))
    return mount.transform_points(local) if local.size else np.zeros((0, 2))


class LidarReturns:
    """One scan's finite returns in base_link, worked out when first asked for and then kept.

    The docking service hears every scan but looks at one only on an approach that watches for obstacles
    and when it picks a dock with the fleet down; turning every scan into points as it arrived cost CPU
    for points it almost never looked at (measurement 71).
    """

    __slots__ = ("_scan", "_points")

    def __init__(
        self, ranges_m: np.ndarray, angle_min_rad: float, angle_increment_rad: float, mount: Pose2D
    ) -> None:
        self._scan: tuple[np.ndarray, float, float, Pose2D] | None = (
            ranges_m,
            angle_min_rad,
            angle_increment_rad,
            mount,
        )
        self._points: np.ndarray | None = None

    @classmethod
    def of_points(cls, points: np.ndarray) -> LidarReturns:
        """Returns already in base_link (tests, tools)."""
        returns = cls(np.zeros(0), 0.0, 0.0, Pose2D(0.0, 0.0, 0.0))
        returns._scan, returns._points = None, np.asarray(points, dtype=float).reshape(-1, 2)
        return returns

    @property
    def points(self) -> np.ndarray:
        """``(N, 2)`` points in base_link."""
        if self._points is None:
            assert self._scan is not None
            self._points = scan_points(*self._scan)
            self._scan = None
        return self._points


def in_dock_region(points: np.ndarray, dock_in_base: Pose2D, margin_m: float) -> np.ndarray:
    """Mask of the points at or behind the dock's plate face, within its width plus ``margin_m``."""
    if points.size == 0:
        return np.zeros(0, dtype=bool)
    in_dock = dock_in_base.inverse().transform_points(points)
    half_width = 0.5 * DOCK_GEOMETRY.body_width_m + margin_m
    return (in_dock[:, 0] >= ROBOT_FRONT_M - margin_m) & (np.abs(in_dock[:, 1]) <= half_width)


def in_corridor(points: np.ndarray, forward: bool, params: ObstacleParams) -> np.ndarray:
    """Mask of the points in the strip the robot sweeps over the next ``stop_distance_m``."""
    if points.size == 0:
        return np.zeros(0, dtype=bool)
    half_length = 0.5 * params.robot_length_m
    half_width = 0.5 * params.robot_width_m + params.side_margin_m
    x, y = points[:, 0], points[:, 1]
    if forward:
        along = (x >= half_length) & (x <= half_length + params.stop_distance_m)
    else:
        along = (x <= -half_length) & (x >= -half_length - params.stop_distance_m)
    return along & (np.abs(y) <= half_width)


def lidar_blocked(
    points: np.ndarray, forward: bool, dock_in_base: Pose2D | None, params: ObstacleParams
) -> bool:
    """Whether any lidar point (base_link) that is not the dock lies in the robot's way."""
    mask = in_corridor(points, forward, params)
    if dock_in_base is not None and mask.any():
        mask &= ~in_dock_region(points, dock_in_base, params.dock_margin_m)
    return bool(mask.any())


def _ray_to_segment(
    origin: tuple[float, float], angle: float, a: tuple[float, float], b: tuple[float, float]
) -> float:
    """Signed distance along the line of the ray from ``origin`` at ``angle`` to segment ``ab``.

    Negative when the segment is behind the origin; inf when the line misses the segment.
    """
    dx, dy = math.cos(angle), math.sin(angle)
    ex, ey = b[0] - a[0], b[1] - a[1]
    denom = dx * ey - dy * ex
    if abs(denom) < 1e-12:
        return math.inf
    wx, wy = a[0] - origin[0], a[1] - origin[1]
    t = (wx * ey - wy * ex) / denom
    s = (wx * dy - wy * dx) / denom
    return t if 0.0 <= s <= 1.0 else math.inf


def expected_sonar_range(dock_in_base: Pose2D, params: ObstacleParams) -> float:
    """The shortest range at which the front ranger's cone meets the dock's plate (within the dock's width
    plus ``dock_margin_m``): 0 when the plate is at or behind the front, inf when the cone misses it."""
    half = 0.5 * DOCK_GEOMETRY.body_width_m + params.dock_margin_m
    a = dock_in_base.transform_point(ROBOT_FRONT_M, -half)
    b = dock_in_base.transform_point(ROBOT_FRONT_M, half)
    origin = (0.5 * params.robot_length_m, 0.0)
    n = params.sonar_rays
    angles = (
        [0.0]
        if n == 1
        else [-0.5 * params.sonar_fov_rad + i * params.sonar_fov_rad / (n - 1) for i in range(n)]
    )
    ranges = [_ray_to_segment(origin, angle, a, b) for angle in angles]
    return max(0.0, min(ranges))


def sonar_blocked(range_m: float, dock_in_base: Pose2D | None, params: ObstacleParams) -> bool:
    """Whether the front ranger's reading is an obstacle short of the stop distance that is not the dock."""
    if not math.isfinite(range_m) or range_m > params.stop_distance_m:
        return False
    if dock_in_base is None:
        return True
    return range_m < expected_sonar_range(dock_in_base, params) - params.sonar_dock_tolerance_m
