"""SE(2) and quaternion helpers on numpy.

Poses in the plane are ``(x, y, yaw)`` with yaw in radians, wrapped to [-pi, pi).
Quaternions are ``(x, y, z, w)`` as in geometry_msgs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def wrap_angle(angle_rad: float) -> float:
    """Wrap an angle to [-pi, pi)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def wrap_angles(angles_rad: np.ndarray) -> np.ndarray:
    """Vectorised :func:`wrap_angle`."""
    return (np.asarray(angles_rad) + np.pi) % (2.0 * np.pi) - np.pi


def quaternion_from_yaw(yaw_rad: float) -> tuple[float, float, float, float]:
    """Quaternion ``(x, y, z, w)`` of a rotation about z."""
    half = 0.5 * yaw_rad
    return (0.0, 0.0, math.sin(half), math.cos(half))


def euler_from_quaternion(x: float, y: float, z: float, w: float) -> tuple[float, float, float]:
    """Roll, pitch, yaw (radians, counter-clockwise) of a quaternion.

    Same formulas as the classic tf listener's ``euler_from_quaternion``, pitch clamped at +-90 degrees.
    """
    t0 = 2.0 * (w * x + y * z)
    t1 = 1.0 - 2.0 * (x * x + y * y)
    roll = math.atan2(t0, t1)
    t2 = max(-1.0, min(1.0, 2.0 * (w * y - z * x)))
    pitch = math.asin(t2)
    t3 = 2.0 * (w * z + x * y)
    t4 = 1.0 - 2.0 * (y * y + z * z)
    yaw = math.atan2(t3, t4)
    return roll, pitch, yaw


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    """Yaw of a quaternion, in [-pi, pi]."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quaternion_multiply(
    a: tuple[float, float, float, float], b: tuple[float, float, float, float]
) -> tuple[float, float, float, float]:
    """Hamilton product ``a * b`` of two ``(x, y, z, w)`` quaternions."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def distances_to_segment(points_xy: np.ndarray, a_xy: np.ndarray, b_xy: np.ndarray) -> np.ndarray:
    """Distance from each of ``(N, 2)`` points to the segment from ``a_xy`` to ``b_xy``."""
    points = np.asarray(points_xy, dtype=float).reshape(-1, 2)
    a, b = np.asarray(a_xy, dtype=float), np.asarray(b_xy, dtype=float)
    ab = b - a
    length2 = float(ab @ ab)
    t = np.zeros(len(points)) if length2 == 0 else np.clip(((points - a) @ ab) / length2, 0.0, 1.0)
    closest = a + t[:, None] * ab
    distances: np.ndarray = np.hypot(points[:, 0] - closest[:, 0], points[:, 1] - closest[:, 1])
    return distances


@dataclass(frozen=True, slots=True)
class Pose2D:
    """A rigid transform in the plane: the pose of a child frame in its parent frame."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    @classmethod
    def from_seq(cls, values: tuple[float, ...] | list[float] | np.ndarray) -> Pose2D:
        x, y, yaw = (float(v) for v in values)
        return cls(x, y, wrap_angle(yaw))

    def as_tuple(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.yaw)

    def compose(self, other: Pose2D) -> Pose2D:
        """``self * other``: the pose ``other`` (given in self's frame) expressed in self's parent."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Pose2D(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            wrap_angle(self.yaw + other.yaw),
        )

    def inverse(self) -> Pose2D:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Pose2D(-c * self.x - s * self.y, s * self.x - c * self.y, wrap_angle(-self.yaw))

    def relative_to(self, frame: Pose2D) -> Pose2D:
        """This pose expressed in ``frame`` (both given in the same parent)."""
        return frame.inverse().compose(self)

    def transform_point(self, px: float, py: float) -> tuple[float, float]:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return (self.x + c * px - s * py, self.y + s * px + c * py)

    def transform_points(self, points: np.ndarray) -> np.ndarray:
        """Transform an ``(N, 2)`` array of points from this frame to its parent."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        rot = np.array([[c, -s], [s, c]])
        moved: np.ndarray = np.asarray(points, dtype=float) @ rot.T + np.array([self.x, self.y])
        return moved

    def distance_to(self, other: Pose2D) -> float:
        return math.hypot(other.x - self.x, other.y - self.y)

    def advance(self, linear_mps: float, angular_radps: float, dt_s: float) -> Pose2D:
        """Where a constant body twist ``(linear_mps, angular_radps)`` takes this pose after ``dt_s``.

        The exact arc of a unicycle (a straight segment when the turn rate is ~0), so a long step loses
        nothing to Euler integration: odometry extrapolation, controller prediction and the kinematic
        test robot all step this way.
        """
        if abs(angular_radps) < 1e-9:
            c, s = math.cos(self.yaw), math.sin(self.yaw)
            return Pose2D(self.x + linear_mps * dt_s * c, self.y + linear_mps * dt_s * s, self.yaw)
        yaw = self.yaw + angular_radps * dt_s
        radius_m = linear_mps / angular_radps
        return Pose2D(
            self.x + radius_m * (math.sin(yaw) - math.sin(self.yaw)),
            self.y - radius_m * (math.cos(yaw) - math.cos(self.yaw)),
            wrap_angle(yaw),
        )

    def interpolate(self, other: Pose2D, fraction: float) -> Pose2D:
        """The pose ``fraction`` of the way to ``other``: linear in position, yaw the shorter way round."""
        return Pose2D(
            self.x + (other.x - self.x) * fraction,
            self.y + (other.y - self.y) * fraction,
            wrap_angle(self.yaw + wrap_angle(other.yaw - self.yaw) * fraction),
        )

    def matrix(self) -> np.ndarray:
        """Homogeneous 3x3 matrix."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([[c, -s, self.x], [s, c, self.y], [0.0, 0.0, 1.0]])
