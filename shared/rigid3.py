"""Rigid transforms in 3-D (rotation matrix and translation), for the few frames that leave the floor plane.

The robot lives in the plane (:class:`~shared.geometry.Pose2D`), but a camera looks from a height and may be
pitched, and its optical frame (REP 103: x right, y down, z ahead) is turned against camera_link. Perception
chains those transforms from ``tf_static``; the simulator publishes them. Pure numpy, no bus.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from shared.geometry import Pose2D

#: camera_link -> camera_optical_frame: the rotation every ROS camera driver publishes (x, y, z, w).
OPTICAL_FROM_LINK_QUATERNION = (-0.5, 0.5, -0.5, 0.5)


def matrix_from_quaternion(x: float, y: float, z: float, w: float) -> np.ndarray:
    """The rotation matrix of a quaternion (normalised first; a zero quaternion is refused)."""
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if not n > 1e-9 or not math.isfinite(n):
        raise ValueError(f"quaternion ({x}, {y}, {z}, {w}) has no rotation (norm {n})")
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def quaternion_from_pitch(pitch_rad: float) -> tuple[float, float, float, float]:
    """A rotation about y (REP 103: a positive pitch tips x down)."""
    return (0.0, math.sin(pitch_rad / 2.0), 0.0, math.cos(pitch_rad / 2.0))


@dataclass(frozen=True, slots=True)
class Rigid3:
    """``p_parent = rotation @ p_child + translation``."""

    rotation: np.ndarray
    translation: np.ndarray

    @classmethod
    def from_parts(
        cls, translation: tuple[float, float, float], quaternion: tuple[float, float, float, float]
    ) -> Rigid3:
        return cls(matrix_from_quaternion(*quaternion), np.asarray(translation, dtype=np.float64))

    def compose(self, child: Rigid3) -> Rigid3:
        """This transform followed by ``child`` (parent <- self.child <- child.child)."""
        return Rigid3(self.rotation @ child.rotation, self.rotation @ child.translation + self.translation)

    def apply(self, point: np.ndarray) -> np.ndarray:
        moved: np.ndarray = self.rotation @ np.asarray(point, dtype=np.float64) + self.translation
        return moved

    def to_pose2d(self) -> Pose2D:
        """The floor-plane pose of this frame, its heading being where its x axis points."""
        return Pose2D(
            float(self.translation[0]),
            float(self.translation[1]),
            math.atan2(self.rotation[1, 0], self.rotation[0, 0]),
        )


__all__ = [
    "OPTICAL_FROM_LINK_QUATERNION",
    "Rigid3",
    "matrix_from_quaternion",
    "quaternion_from_pitch",
]
