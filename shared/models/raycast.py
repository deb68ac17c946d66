"""Vectorised ray casting against line segments, the core of every simulated range sensor.

Each ray ``o + t d`` (``|d| = 1``) meets segment ``p + u s`` where both parametric equations agree; solving
with 2-D cross products gives ``t = (q x s) / (d x s)`` and ``u = (q x d) / (d x s)`` with ``q = p - o``
(the classic ray/segment test, e.g. Schneider & Eberly, *Geometric Tools for Computer Graphics*, 7.1).
All rays against all segments is one ``(rays, segments)`` array operation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from shared.world import Segment


class SegmentSet:
    """Segments packed once as ``(1, M)`` rows (start ``p``, direction ``s``), for casting many rays."""

    def __init__(self, segments: Sequence[Segment]):
        arr = np.asarray(segments, dtype=float).reshape(-1, 2, 2)
        self._set(arr[:, 0, :], arr[:, 1, :] - arr[:, 0, :])

    def _set(self, start: np.ndarray, delta: np.ndarray) -> None:
        self.start = start  # (M, 2)
        self.delta = delta  # (M, 2)
        self.px, self.py = start[None, :, 0], start[None, :, 1]
        self.sx, self.sy = delta[None, :, 0], delta[None, :, 1]

    def __len__(self) -> int:
        return len(self.start)

    @classmethod
    def from_arrays(cls, start: np.ndarray, delta: np.ndarray) -> SegmentSet:
        """Segments already packed: ``start`` and ``delta`` (direction times length), each ``(M, 2)``."""
        made = cls([])
        made._set(start, delta)
        return made

    @classmethod
    def concat(cls, *sets: SegmentSet) -> SegmentSet:
        if not sets:
            return cls([])
        return cls.from_arrays(
            np.concatenate([s.start for s in sets]), np.concatenate([s.delta for s in sets])
        )


def cast_rays(origin_xy: tuple[float, float], angles_rad: np.ndarray, segments: SegmentSet) -> np.ndarray:
    """Distance from ``origin_xy`` along each world-frame angle to the nearest segment; ``inf`` if none."""
    angles = np.asarray(angles_rad, dtype=float)
    if len(segments) == 0:
        return np.full(angles.shape, np.inf)
    dx = np.cos(angles)[:, None]  # (N, 1)
    dy = np.sin(angles)[:, None]
    qx = segments.px - origin_xy[0]  # (1, M)
    qy = segments.py - origin_xy[1]
    q_cross_s = qx * segments.sy - qy * segments.sx  # (1, M): the same for every ray
    denom = dx * segments.sy - dy * segments.sx  # d x s, (N, M)
    denom[denom == 0.0] = np.nan  # parallel: no hit (nan compares false, silently)
    t = q_cross_s / denom
    u = (qx * dy - qy * dx) / denom
    hit = (t >= 0.0) & (u >= 0.0) & (u <= 1.0)
    nearest: np.ndarray = np.where(hit, t, np.inf).min(axis=1)
    return nearest


def segment_blocked(
    a_xy: tuple[float, float], b_xy: tuple[float, float], segments: SegmentSet, end_margin: float = 1e-6
) -> bool:
    """Whether any segment crosses the open line of sight from ``a`` to ``b``.

    Crossings within ``end_margin`` (as a fraction of the length) of either end do not count, so a target
    lying on a surface (a marker on a face) is not hidden by that surface.
    """
    if len(segments) == 0:
        return False
    dx, dy = b_xy[0] - a_xy[0], b_xy[1] - a_xy[1]
    sx, sy = segments.delta[:, 0], segments.delta[:, 1]
    qx, qy = segments.start[:, 0] - a_xy[0], segments.start[:, 1] - a_xy[1]
    denom = dx * sy - dy * sx
    denom = np.where(denom == 0.0, np.nan, denom)
    t = (qx * sy - qy * sx) / denom
    u = (qx * dy - qy * dx) / denom
    crossing = (t > end_margin) & (t < 1.0 - end_margin) & (u >= 0.0) & (u <= 1.0)
    return bool(crossing.any())


def nearest_in_cone(
    origin_xy: tuple[float, float], yaw_rad: float, half_angle_rad: float, segments: SegmentSet
) -> float:
    """Distance from ``origin_xy`` to the nearest point of any segment inside the cone; ``inf`` if none.

    See :func:`distances_in_cone`, which gives each segment's distance.
    """
    distance = distances_in_cone(origin_xy, yaw_rad, half_angle_rad, segments)
    return float(distance.min()) if len(distance) else math.inf


def distances_in_cone(
    origin_xy: tuple[float, float], yaw_rad: float, half_angle_rad: float, segments: SegmentSet
) -> np.ndarray:
    """Each segment's distance from ``origin_xy`` inside the cone, ``(M,)``: ``inf`` wholly outside it.

    An ultrasonic ping fills its whole cone, and the first echo back comes from the nearest surface
    anywhere in it. A fan of rays misses what lies between them: a pane seen end-on, 8 cm wide at 1 m
    between seven rays across 0.5 rad, is open floor to such a fan until the robot is upon it. Here each
    segment is clipped to the cone (for ``half_angle_rad`` below pi/2 the cone is the intersection of two
    half-planes through the apex, so the clip is Liang-Barsky's on two edges), then the clipped part's
    point nearest the apex is taken.
    """
    if not 0.0 < half_angle_rad < 0.5 * math.pi:
        raise ValueError(f"a cone's half angle must lie in (0, pi/2), got {half_angle_rad}")
    ax = segments.start[:, 0] - origin_xy[0]  # (M,), apex at the origin
    ay = segments.start[:, 1] - origin_xy[1]
    dx, dy = segments.delta[:, 0], segments.delta[:, 1]
    lo = np.zeros(len(segments))
    hi = np.ones(len(segments))
    # Inside the cone: left of its right edge (cross(right, p) >= 0), right of its left edge (cross(left, p) <= 0).
    for edge_angle, sign in ((yaw_rad - half_angle_rad, 1.0), (yaw_rad + half_angle_rad, -1.0)):
        ux, uy = math.cos(edge_angle), math.sin(edge_angle)
        at_start = sign * (ux * ay - uy * ax)  # g(t) = at_start + t * rate must stay >= 0
        rate = sign * (ux * dy - uy * dx)
        with np.errstate(divide="ignore", invalid="ignore"):
            crossing = -at_start / rate
        lo = np.where(rate > 0.0, np.maximum(lo, crossing), lo)
        hi = np.where(rate < 0.0, np.minimum(hi, crossing), hi)
        outside = (rate == 0.0) & (at_start < 0.0)  # parallel to the edge and on its far side
        hi = np.where(outside, -1.0, hi)
    inside = lo <= hi
    length_sq = dx * dx + dy * dy
    with np.errstate(divide="ignore", invalid="ignore"):
        closest = np.where(length_sq > 0.0, -(ax * dx + ay * dy) / length_sq, 0.0)
    t = np.clip(closest, lo, hi)
    distance = np.hypot(ax + t * dx, ay + t * dy)
    return np.where(inside, distance, np.inf)
