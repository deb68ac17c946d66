"""Exact Euclidean distance to the nearest marked cell, up to a cut-off, in pure numpy.

Two passes in the spirit of Meijster et al. (2000), "A general algorithm for computing distance
transforms in linear time": first the distance ``g`` to the nearest mark along each row (prefix
max/min scans), then ``d^2(x, y) = min over dy of g(x, y+dy)^2 + dy^2``. Bounding ``|dy|`` by the
cut-off keeps the second pass to ``2 * cut-off`` vectorised minima, and it stays exact for every
distance up to the cut-off (a mark within that distance is at most that many rows away).
"""

from __future__ import annotations

import math

import numpy as np


def squared_distance_to_marks(marks: np.ndarray, max_distance_cells: float) -> np.ndarray:
    """Squared distance (in cells, between cell centres) from every cell to the nearest ``True`` cell.

    Exact wherever the distance is at most ``max_distance_cells``; everywhere else the value is only
    known to be larger than ``max_distance_cells ** 2``. Returns int32 ``(height, width)``.

    Only the marks' bounding box, widened by the cut-off, is computed: every cell outside it is farther
    than the cut-off from every mark (a few glass marks in a large hall cost a few cells, not the hall).
    """
    marks = np.asarray(marks, dtype=bool)
    if marks.ndim != 2:
        raise ValueError(f"marks must be a 2-D array, got shape {marks.shape}")
    if not (max_distance_cells >= 0):
        raise ValueError(f"max_distance_cells must be non-negative, got {max_distance_cells}")
    reach = int(math.floor(max_distance_cells)) + 1  # any row offset or distance beyond this is "far"
    far = reach * reach
    window = bounds_of(marks, reach)
    if window is None:
        return np.full(marks.shape, far, dtype=np.int32)
    if marks[window].size == marks.size:
        return _squared_distance_within(marks, reach)
    out = np.full(marks.shape, far, dtype=np.int32)
    out[window] = _squared_distance_within(marks[window], reach)
    return out


def bounds_of(mask: np.ndarray, margin: int) -> tuple[slice, slice] | None:
    """The rows and columns of ``mask``'s ``True`` cells' bounding box widened by ``margin`` cells on
    every side (clipped to the grid); None when no cell is set."""
    rows, columns = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if len(rows) == 0:
        return None
    height, width = mask.shape
    return (
        slice(max(0, int(rows[0]) - margin), min(height, int(rows[-1]) + 1 + margin)),
        slice(max(0, int(columns[0]) - margin), min(width, int(columns[-1]) + 1 + margin)),
    )


def _squared_distance_within(marks: np.ndarray, reach: int) -> np.ndarray:
    """The two passes over the whole of ``marks`` (at least one set), capped at ``reach ** 2``."""
    height, width = marks.shape
    far = reach * reach
    columns = np.arange(width, dtype=np.int32)
    none = np.int32(4 * (width + height + reach))
    left = np.maximum.accumulate(np.where(marks, columns, -none), axis=1)
    right = np.minimum.accumulate(np.where(marks, columns, none)[:, ::-1], axis=1)[:, ::-1]
    row_distance = np.minimum(np.minimum(columns - left, right - columns), reach).astype(np.int32)
    g2 = row_distance * row_distance

    d2 = g2.copy()
    for dy in range(1, min(reach, height)):
        shifted = g2[:-dy] + dy * dy
        np.minimum(d2[dy:], shifted, out=d2[dy:])
        shifted = g2[dy:] + dy * dy
        np.minimum(d2[:-dy], shifted, out=d2[:-dy])
    return np.minimum(d2, far)


def distance_to_marks(marks: np.ndarray, max_distance_cells: float) -> np.ndarray:
    """Euclidean distance in cells to the nearest ``True`` cell; ``inf`` beyond ``max_distance_cells``."""
    d = np.sqrt(squared_distance_to_marks(marks, max_distance_cells).astype(float))
    d[d > max_distance_cells] = np.inf
    return d
