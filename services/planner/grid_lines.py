"""Which grid cells a segment or a ray touches, vectorised over numpy.

Two rules, for two jobs:

- :func:`segment_cells` is the conservative "supercover": every cell whose interior the segment crosses,
  4-connected (a step through a cell corner adds one side cell), so a drawn wall has no diagonal gaps
  and a line-of-sight test cannot slip between two occupied cells.
- :func:`ray_cells` is the digital differential analyser between cell centres that costmaps use for
  raytracing (Bresenham's line, as in nav2_costmap_2d ``raytraceLine``): 8-connected, one cell per
  step along the major axis, so clearing does not wipe cells the beam only grazed.

Coordinates are continuous grid coordinates (cells; cell ``i`` spans ``[i, i+1)``), see
:meth:`GridFrame.world_to_grid`.
"""

from __future__ import annotations

import numpy as np

#: Same nudge as :meth:`GridFrame.world_to_cells`: a point on a cell edge belongs to the upper cell.
_EDGE_EPS = 1e-9


def segment_cells(start_grid: np.ndarray, end_grid: np.ndarray) -> np.ndarray:
    """``(N, 2)`` integer cells ``(ix, iy)`` crossed by a segment, in order from start to end, 4-connected."""
    p0 = np.asarray(start_grid, dtype=float).reshape(2)
    p1 = np.asarray(end_grid, dtype=float).reshape(2)
    d = p1 - p0
    # Parameters where the segment crosses a vertical or a horizontal grid line.
    ts = [np.array([0.0, 1.0])]
    for axis in (0, 1):
        if d[axis] != 0.0:
            lo, hi = sorted((p0[axis], p1[axis]))
            lines = np.arange(np.floor(lo) + 1.0, np.ceil(hi))
            ts.append((lines - p0[axis]) / d[axis])
    t = np.unique(np.clip(np.concatenate(ts), 0.0, 1.0))
    mids = np.concatenate([[0.0], 0.5 * (t[:-1] + t[1:]), [1.0]])
    cells = np.floor(p0 + mids[:, None] * d + _EDGE_EPS).astype(np.int64)
    keep = np.ones(len(cells), dtype=bool)
    keep[1:] = np.any(cells[1:] != cells[:-1], axis=1)
    cells = cells[keep]
    # Through an exact cell corner the sequence jumps diagonally: add the side cell that keeps it 4-connected.
    diagonal = np.all(cells[1:] != cells[:-1], axis=1)
    if np.any(diagonal):
        idx = np.nonzero(diagonal)[0]
        side = np.stack([cells[idx + 1, 0], cells[idx, 1]], axis=1)
        cells = np.insert(cells, idx + 1, side, axis=0)
    return cells


def ray_cells(
    start_cell: np.ndarray, end_cells: np.ndarray, include_end: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Cells on the Bresenham lines from one cell to each of ``(N, 2)`` end cells.

    Returns ``(cells (M, 2), ray_index (M,))``: the cells of all rays, start cell first on each ray,
    and which ray each belongs to. With ``include_end=False`` each ray stops one cell short of its end
    (the hit cell, which a clearing pass must not free).
    """
    start = np.asarray(start_cell, dtype=np.int64).reshape(2)
    ends = np.asarray(end_cells, dtype=np.int64).reshape(-1, 2)
    if len(ends) == 0:
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64)
    delta = ends - start
    steps = np.abs(delta).max(axis=1)
    last = steps if include_end else steps - 1
    k = np.arange(int(steps.max()) + 1)
    mask = k[None, :] <= last[:, None]
    frac = k[None, :] / np.maximum(steps, 1)[:, None]
    ix = start[0] + np.rint(frac * delta[:, 0:1]).astype(np.int64)
    iy = start[1] + np.rint(frac * delta[:, 1:2]).astype(np.int64)
    ray_index = np.broadcast_to(np.arange(len(ends))[:, None], mask.shape)
    return np.stack([ix[mask], iy[mask]], axis=1), ray_index[mask]
