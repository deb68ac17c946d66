"""How far the robot has to drive to each dock: shortest paths through the room's free space.

The fleet hands out the nearest free dock by path length, not by straight-line distance: in a room with
shelving the dock just behind a rack may be the far one. The docking service knows the room from its
world file (walls, boxes, dock bodies and glass; not other robots, which move): a grid over the room
(:data:`GRID_M`) whose cells are free where the robot's centre keeps :data:`CLEARANCE_M` from every
surface, searched from the robot's cell by Dijkstra (8 neighbours), gives the length to each dock's
staging pose, plus the last straight leg into the dock.

Pure: no bus. One search serves every dock.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Sequence

import numpy as np

from shared.geometry import Pose2D, distances_to_segment

GRID_M = 0.1
#: The robot's half width (0.15 m) and a margin: the centre keeps this far from every surface.
CLEARANCE_M = 0.2

Segment = tuple[tuple[float, float], tuple[float, float]]
_STEPS = [(di, dj, math.hypot(di, dj)) for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj]


class RoomPaths:
    """The room's free cells, prepared once; :meth:`lengths` searches from a start."""

    def __init__(self, bounds: tuple[float, float, float, float], walls: Sequence[Segment]) -> None:
        xmin, ymin, xmax, ymax = bounds
        self.origin = (xmin, ymin)
        self.shape = (
            max(1, int(math.ceil((ymax - ymin) / GRID_M))),
            max(1, int(math.ceil((xmax - xmin) / GRID_M))),
        )
        rows, cols = self.shape
        ys, xs = np.mgrid[0:rows, 0:cols]
        centres = np.column_stack([(xs.ravel() + 0.5) * GRID_M + xmin, (ys.ravel() + 0.5) * GRID_M + ymin])
        clearance = np.full(len(centres), np.inf)
        for a, b in walls:
            clearance = np.minimum(
                clearance, distances_to_segment(centres, np.asarray(a, float), np.asarray(b, float))
            )
        self.free = (clearance >= CLEARANCE_M).reshape(self.shape)

    def _cell(self, x: float, y: float) -> tuple[int, int] | None:
        i = int((y - self.origin[1]) / GRID_M)
        j = int((x - self.origin[0]) / GRID_M)
        if 0 <= i < self.shape[0] and 0 <= j < self.shape[1]:
            return i, j
        return None

    def _nearest_free(self, x: float, y: float) -> tuple[int, int] | None:
        """The free cell nearest ``(x, y)`` within 0.3 m (a pose hard by a wall still counts)."""
        cell = self._cell(x, y)
        if cell is None:
            return None
        i0, j0 = cell
        best: tuple[float, tuple[int, int]] | None = None
        for di in range(-3, 4):
            for dj in range(-3, 4):
                i, j = i0 + di, j0 + dj
                if 0 <= i < self.shape[0] and 0 <= j < self.shape[1] and self.free[i, j]:
                    d = math.hypot(di, dj)
                    if best is None or d < best[0]:
                        best = (d, (i, j))
        return best[1] if best is not None else None

    def lengths(self, start: Pose2D, goals: Sequence[Pose2D]) -> list[float]:
        """The shortest free path length (m) from ``start`` to each goal; inf where none connects."""
        source = self._nearest_free(start.x, start.y)
        targets = [self._nearest_free(g.x, g.y) for g in goals]
        if source is None:
            return [math.inf] * len(goals)
        wanted = {t for t in targets if t is not None}
        dist = np.full(self.shape, np.inf)
        dist[source] = 0.0
        heap = [(0.0, source)]
        rows, cols = self.shape
        while heap and wanted:
            d, (i, j) = heapq.heappop(heap)
            if d > dist[i, j]:
                continue
            wanted.discard((i, j))
            for di, dj, step in _STEPS:
                ni, nj = i + di, j + dj
                if 0 <= ni < rows and 0 <= nj < cols and self.free[ni, nj] and d + step < dist[ni, nj]:
                    dist[ni, nj] = d + step
                    heapq.heappush(heap, (d + step, (ni, nj)))
        return [float(dist[t]) * GRID_M if t is not None else math.inf for t in targets]
