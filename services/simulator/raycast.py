"""Vectorised ray casting against line segments, the core of every simulated range sensor.

Each ray ``o + t d`` (``|d| = 1``) meets segment ``p + u s`` where both parametric equations agree; solving
with 2-D cross products gives ``t = (q x s) / (d x s)`` and ``u = (q x d) / (d x s)`` with ``q = p - o``
(the classic ray/segment test, e.g. Schneider & Eberly, *Geometric Tools for Computer Graphics*, 7.1).
All rays against all segments is one ``(rays, segments)`` array operation.
"""

from __future__ import annotations

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
    def concat(cls, *sets: SegmentSet) -> SegmentSet:
        merged = cls([])
        if sets:
            merged._set(np.concatenate([s.start for s in sets]), np.concatenate([s.delta for s in sets]))
        return merged


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
    return np.where(hit, t, np.inf).min(axis=1)


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
