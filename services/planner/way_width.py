"""How wide the widest way between two places is at its narrowest: the gap a robot must pass to get there.

A room can be reachable for the robot's inscribed circle (what :mod:`services.planner.lower_bound` asks)
and still be reached only through a gap between two glass panes a few centimetres wider than the robot,
where sonar marks a few centimetres off close the way. This module measures that gap, so a campaign can
say which rooms demand it (measurement 109 has what it showed in the generated glass rooms).

The way's width is a widest-path search ("maximin") from the goal over the free cells of a rasterised
world, glass as solid as any wall: each cell keeps the best clearance any way from the goal can keep to
reach it, the clearance of a cell being the distance between its centre and the nearest solid cell's.
The width of a way is twice the clearance of its tightest cell: a gap between two segments of the world
(which have no thickness) comes out within a cell of its true width. Each end is given ``end_radius_m`` of
free play: a docking pose stands closer to the dock than any gap on the way, and a start may stand near a
wall it drives away from.

Pure numpy and ``heapq``: no bus, no thread.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Sequence

import numpy as np

from services.planner.distance_transform import squared_distance_to_marks
from services.planner.occupancy_map import OCC_FREE, OccupancyMap

#: Clearances are measured up to this far (a way wider than twice this is "wide": its width is capped).
MAX_CLEARANCE_M = 1.5
#: Free play round each end of the way (see the module docstring).
END_RADIUS_M = 0.5

_NEIGHBOURS = ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1))


class WayWidths:
    """The widest ways from every free cell of ``occupancy`` to ``goal_xy``, searched once."""

    def __init__(
        self,
        occupancy: OccupancyMap,
        goal_xy: tuple[float, float],
        end_radius_m: float = END_RADIUS_M,
        max_clearance_m: float = MAX_CLEARANCE_M,
    ) -> None:
        frame = occupancy.frame
        self._frame = frame
        self._end_radius_m = end_radius_m
        self._max_width_m = 2.0 * max_clearance_m
        solid = occupancy.data != OCC_FREE  # occupied, and unknown (outside the room)
        max_cells = max_clearance_m / frame.resolution_m
        clearance = np.sqrt(squared_distance_to_marks(solid, max_cells)) * frame.resolution_m
        clearance = np.minimum(clearance, max_clearance_m)
        goal_play = frame.cells_within(goal_xy, end_radius_m)
        clearance[goal_play[:, 1], goal_play[:, 0]] = math.inf  # solid cells among them stay unvisited
        self._best = _widest_from(clearance, solid, frame.world_to_cell(*goal_xy))

    def width_m(self, start_xy: tuple[float, float]) -> float:
        """The width of the widest way from ``start_xy`` to the goal at its narrowest (m); 0.0 when no way
        joins them; at most twice :data:`MAX_CLEARANCE_M`, however open the room (or when the start stands
        within the goal's free play)."""
        play = self._frame.cells_within(start_xy, self._end_radius_m)
        best = float(self._best[play[:, 1], play[:, 0]].max(initial=-1.0))  # -1: solid or no way
        return 0.0 if best <= 0.0 else min(self._max_width_m, 2.0 * best)


def way_widths(
    occupancy: OccupancyMap, goal_xy: tuple[float, float], starts_xy: Sequence[tuple[float, float]]
) -> list[float]:
    """:meth:`WayWidths.width_m` of each start, one search for all of them."""
    widths = WayWidths(occupancy, goal_xy)
    return [widths.width_m(start) for start in starts_xy]


def _widest_from(clearance: np.ndarray, solid: np.ndarray, goal_cell: tuple[int, int]) -> np.ndarray:
    """Per cell, the largest ``min(clearance)`` along any 8-connected way of free cells from ``goal_cell``
    (-1: no way; a solid goal cell reaches nothing). Dijkstra's search with the bottleneck for a cost."""
    height, width = clearance.shape
    best = np.full((height, width), -1.0)
    gx, gy = goal_cell
    if not (0 <= gx < width and 0 <= gy < height) or solid[gy, gx]:
        return best
    best[gy, gx] = clearance[gy, gx]
    heap: list[tuple[float, int, int]] = [(-clearance[gy, gx], gx, gy)]
    free = ~solid
    while heap:
        negative, x, y = heapq.heappop(heap)
        value = -negative
        if value < best[y, x]:
            continue  # a wider way reached this cell after this entry was queued
        for dx, dy in _NEIGHBOURS:
            nx, ny = x + dx, y + dy
            if 0 <= nx < width and 0 <= ny < height and free[ny, nx]:
                through = min(value, clearance[ny, nx])
                if through > best[ny, nx]:
                    best[ny, nx] = through
                    heapq.heappush(heap, (-through, nx, ny))
    return best
