"""Turn a grid path into a smooth, evenly spaced path with orientations, without making it less safe.

Three steps:

1. Cost-aware line-of-sight shortcutting (the "string pulling" post-process of Theta*-style planners):
   a vertex is skipped when the straight segment crosses no cell above the allowed cost and its
   traversal cost (same weighting as A*) is no higher than the stretch of path it replaces, so
   shortcuts remove grid zig-zags but never pull the path closer to obstacles than A* chose.
2. Resampling at ``spacing_m``.
3. Light gradient smoothing (data + smoothness terms, as in PythonRobotics' path smoothing), with any
   smoothed stretch that would cross a more expensive cell put back where it was.

The allowed cost of a segment is ``max_cost`` or, where the grid path itself ran costlier (a start
inside inflation), the cost the grid path had there; inscribed, lethal and (unless allowed) unknown
cells are never allowed. Orientations follow the direction of travel; the last pose takes the goal yaw.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from services.planner.costmap import INSCRIBED_INFLATED_OBSTACLE, MAX_NON_OBSTACLE, NO_INFORMATION, CostGrid
from services.planner.grid_lines import segment_cells


@dataclass(frozen=True)
class SmoothingParams:
    #: Shortcuts and smoothing may cross cells up to this cost (and never inscribed or lethal ones).
    max_cost: int = 200
    #: Same weighting as :class:`services.planner.astar.AStarParams.cost_weight`.
    cost_weight: float = 3.0
    spacing_m: float = 0.05
    data_weight: float = 0.1
    smooth_weight: float = 0.3
    iterations: int = 60
    allow_unknown: bool = False

    def __post_init__(self) -> None:
        if not (0 <= self.max_cost < INSCRIBED_INFLATED_OBSTACLE):
            raise ValueError(f"max_cost must be in 0..252, got {self.max_cost}")
        if not (math.isfinite(self.spacing_m) and self.spacing_m > 0):
            raise ValueError(f"spacing_m must be a positive number, got {self.spacing_m}")
        if not (0 <= self.data_weight <= 1 and 0 <= self.smooth_weight <= 0.45):
            raise ValueError(
                "data_weight must be in [0, 1] and smooth_weight in [0, 0.45] for a stable smoother"
            )
        if self.iterations < 0:
            raise ValueError(f"iterations must be non-negative, got {self.iterations}")


def path_length_m(points_xy: np.ndarray) -> float:
    pts = np.asarray(points_xy, dtype=float)
    return float(np.hypot(*np.diff(pts[:, :2], axis=0).T).sum()) if len(pts) > 1 else 0.0


def _ranked(costs: np.ndarray, allow_unknown: bool) -> np.ndarray:
    """Costs on one scale for "may I cross this": unknown is free when allowed, else worse than lethal."""
    costs = np.asarray(costs).astype(np.int16)
    return np.where(costs == NO_INFORMATION, 0 if allow_unknown else 256, costs)


def _sample_segments(
    points_xy: np.ndarray, step_m: float, include_end: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points along each segment, no more than ``step_m`` apart, start included (end too if asked).

    Returns ``(samples (M, 2), segment index (M,) in ascending order, length each sample stands for (M,))``.
    """
    starts, ends = points_xy[:-1], points_xy[1:]
    lengths = np.hypot(*(ends - starts).T)
    counts = np.maximum(1, np.ceil(lengths / step_m)).astype(np.int64)
    per_segment = counts + 1 if include_end else counts
    seg = np.repeat(np.arange(len(starts)), per_segment)
    first = np.repeat(np.cumsum(per_segment) - per_segment, per_segment)
    frac = (np.arange(len(seg)) - first) / counts[seg]
    samples = starts[seg] + (ends - starts)[seg] * frac[:, None]
    return samples, seg, (lengths / counts)[seg]


class _CostField:
    """Cost queries on one grid, with the smoother's crossing rules."""

    def __init__(self, grid: CostGrid, params: SmoothingParams) -> None:
        self.grid = grid
        self.params = params
        self.step_m = 0.25 * grid.frame.resolution_m

    def segment_max(self, a: np.ndarray, b: np.ndarray) -> int:
        """Highest ranked cost of any cell the segment crosses (supercover; off-grid is impassable)."""
        frame = self.grid.frame
        cells = segment_cells(*frame.world_to_grid(np.array([a, b])))
        if not frame.cells_in_bounds(cells).all():
            return 256
        return int(_ranked(self.grid.costs[cells[:, 1], cells[:, 0]], self.params.allow_unknown).max())

    def traversal_cost(self, points_xy: np.ndarray) -> np.ndarray:
        """Cumulative A*-style traversal cost at each vertex of a polyline (first vertex 0)."""
        if len(points_xy) < 2:
            return np.zeros(len(points_xy))
        samples, seg, ds = _sample_segments(points_xy, self.step_m)
        ranked = np.minimum(_ranked(self.grid.costs_at(samples), self.params.allow_unknown), MAX_NON_OBSTACLE)
        per_sample = ds * (1.0 + self.params.cost_weight * ranked / MAX_NON_OBSTACLE)
        per_segment = np.bincount(seg, weights=per_sample, minlength=len(points_xy) - 1)
        return np.concatenate([[0.0], np.cumsum(per_segment)])

    def segment_maxima(self, points_xy: np.ndarray) -> np.ndarray:
        """Highest ranked cost sampled along each segment of a polyline, both ends included."""
        samples, seg, _ = _sample_segments(points_xy, self.step_m, include_end=True)
        ranked = _ranked(self.grid.costs_at(samples), self.params.allow_unknown)
        starts = np.searchsorted(seg, np.arange(len(points_xy) - 1))
        return np.maximum.reduceat(ranked, starts)


def shortcut_path(grid: CostGrid, points_xy: np.ndarray, params: SmoothingParams | None = None) -> np.ndarray:
    """Cost-aware line-of-sight shortcutting of a polyline; returns the kept vertices ``(K, 2)``."""
    params = params or SmoothingParams()
    pts = np.asarray(points_xy, dtype=float).reshape(-1, 2)
    n = len(pts)
    if n <= 2:
        return pts.copy()
    field = _CostField(grid, params)
    cumulative = field.traversal_cost(pts)
    seg_max = field.segment_maxima(pts)
    # Sampling phase differs between a stretch and its shortcut; half a free cell of slack absorbs it.
    slack = 0.5 * grid.frame.resolution_m

    def visible(i: int, j: int) -> bool:
        limit = min(max(params.max_cost, int(seg_max[i:j].max())), INSCRIBED_INFLATED_OBSTACLE - 1)
        if field.segment_max(pts[i], pts[j]) > limit:
            return False
        direct = field.traversal_cost(pts[[i, j]])[-1]
        return bool(direct <= cumulative[j] - cumulative[i] + slack)

    kept = [0]
    anchor = 0
    while anchor < n - 1:
        # The grid path's own next vertex is always reachable; gallop outwards, then bisect.
        good, offset, bad = anchor + 1, 2, -1
        while bad < 0 and good < n - 1:
            probe = min(anchor + offset, n - 1)
            if visible(anchor, probe):
                good, offset = probe, 2 * offset
            else:
                bad = probe
        while bad - good > 1:
            mid = (good + bad) // 2
            if visible(anchor, mid):
                good = mid
            else:
                bad = mid
        kept.append(good)
        anchor = good
    return pts[kept]


def resample_path(points_xy: np.ndarray, spacing_m: float) -> np.ndarray:
    """Points every ``spacing_m`` or a little less along a polyline, both ends kept."""
    pts = np.asarray(points_xy, dtype=float).reshape(-1, 2)
    if len(pts) < 2:
        return pts.copy()
    seg_len = np.hypot(*np.diff(pts, axis=0).T)
    keep = np.concatenate([[True], seg_len > 1e-12])
    pts = pts[keep]
    if len(pts) < 2:
        return pts[:1].copy()
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    count = max(1, math.ceil(s[-1] / spacing_m - 1e-9))
    targets = np.linspace(0.0, s[-1], count + 1)
    return np.stack([np.interp(targets, s, pts[:, 0]), np.interp(targets, s, pts[:, 1])], axis=1)


def gradient_smooth(
    points_xy: np.ndarray, data_weight: float, smooth_weight: float, iterations: int
) -> np.ndarray:
    """Pull interior points towards their neighbours' midpoint while tethering them to the input."""
    original = np.asarray(points_xy, dtype=float)
    smoothed = original.copy()
    if len(smoothed) < 3:
        return smoothed
    for _ in range(iterations):
        inner = smoothed[1:-1]
        inner += data_weight * (original[1:-1] - inner) + smooth_weight * (
            smoothed[:-2] + smoothed[2:] - 2.0 * inner
        )
    return smoothed


def orientations(points_xy: np.ndarray, goal_yaw_rad: float | None) -> np.ndarray:
    """Yaw of travel at each point (central differences); the last point takes ``goal_yaw_rad``."""
    pts = np.asarray(points_xy, dtype=float)
    n = len(pts)
    if n == 1:
        return np.array([0.0 if goal_yaw_rad is None else goal_yaw_rad])
    ahead = np.concatenate([pts[1:], pts[-1:]])
    behind = np.concatenate([pts[:1], pts[:-1]])
    d = ahead - behind
    yaw = np.arctan2(d[:, 1], d[:, 0])
    if goal_yaw_rad is not None:
        yaw[-1] = goal_yaw_rad
    return (yaw + math.pi) % (2.0 * math.pi) - math.pi


def smooth_path(
    grid: CostGrid,
    points_xy: np.ndarray,
    goal_yaw_rad: float | None = None,
    params: SmoothingParams | None = None,
) -> np.ndarray:
    """Shortcut, resample and smooth a grid path; returns poses ``(N, 3)`` about ``spacing_m`` apart."""
    params = params or SmoothingParams()
    pts = np.asarray(points_xy, dtype=float).reshape(-1, 2)
    if len(pts) == 0:
        raise ValueError("cannot smooth an empty path")
    coarse = shortcut_path(grid, pts, params)
    dense = resample_path(coarse, params.spacing_m)
    if len(dense) >= 3 and params.iterations > 0:
        dense = _smooth_within_costs(grid, dense, params)
    return np.column_stack([dense, orientations(dense, goal_yaw_rad)])


def _smooth_within_costs(grid: CostGrid, dense: np.ndarray, params: SmoothingParams) -> np.ndarray:
    field = _CostField(grid, params)
    before = field.segment_maxima(dense)
    # Never above max_cost or into inscribed space, unless the unsmoothed path already was there.
    limit = np.maximum(
        np.minimum(np.maximum(before, params.max_cost), INSCRIBED_INFLATED_OBSTACLE - 1), before
    )
    # A smoothed segment may also use the allowance of its neighbours (points shift along the path).
    padded = np.concatenate([[limit[0]], limit, [limit[-1]]])
    limit = np.maximum(np.maximum(padded[:-2], padded[1:-1]), padded[2:])
    smoothed = gradient_smooth(dense, params.data_weight, params.smooth_weight, params.iterations)
    # Where smoothing would cross a costlier cell, pin the path back to where it was and blend the
    # smoothing back in over a few points on either side, so the fix leaves no kink.
    pinned = np.zeros(len(dense), dtype=bool)
    candidate = smoothed
    for _ in range(8):
        bad = np.nonzero(field.segment_maxima(candidate) > limit)[0]
        if len(bad) == 0:
            return candidate
        for k in bad:
            pinned[max(0, k - 2) : k + 4] = True
        candidate = dense + _blend_away_from(pinned, _BLEND_POINTS)[:, None] * (smoothed - dense)
    return dense


#: How many points the smoothing takes to fade back in next to a pinned stretch.
_BLEND_POINTS = 10


def _blend_away_from(pinned: np.ndarray, ramp_points: int) -> np.ndarray:
    """0 at pinned points, rising linearly to 1 at ``ramp_points`` away from the nearest one."""
    index = np.arange(len(pinned))
    pins = np.nonzero(pinned)[0]
    after = np.searchsorted(pins, index)
    right = np.abs(pins[np.minimum(after, len(pins) - 1)] - index)
    left = np.abs(index - pins[np.maximum(after - 1, 0)])
    return np.clip(np.minimum(left, right) / ramp_points, 0.0, 1.0)
