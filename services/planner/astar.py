"""Cost-aware A* on a costmap grid: 8-connected, octile heuristic (Hart, Nilsson & Raphael, 1968).

Entering a cell costs ``step_m * (1 + cost_weight * cost / 252)`` with ``step_m`` the resolution or
``sqrt(2)`` times it, so the search prefers the middle of corridors the way Nav2's NavFn/Smac 2D do.
Cells at or above :data:`INSCRIBED_INFLATED_OBSTACLE` are never entered, nor unknown cells unless
``allow_unknown`` (then they cost like free space). A diagonal step is allowed only when both cells it
squeezes between are enterable, so paths never cut an obstacle's corner. The octile distance is
admissible and consistent (every multiplier is at least 1), so the returned path is optimal.

Start and goal that sit on a blocked cell are snapped to the nearest enterable cell within
``snap_radius_m``; otherwise :class:`PlanningError` says which end is blocked and why.
"""

from __future__ import annotations

import heapq
import math
from array import array
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from services.planner.costmap import INSCRIBED_INFLATED_OBSTACLE, MAX_NON_OBSTACLE, NO_INFORMATION, CostGrid

_SQRT2 = math.sqrt(2.0)


class PlanningError(RuntimeError):
    """No path: an end is off the map or blocked with nothing free nearby, or the goal is unreachable."""


@dataclass(frozen=True)
class AStarParams:
    #: How strongly inflation cost lengthens a step: 0 is pure shortest path.
    cost_weight: float = 3.0
    #: Move a blocked start or goal to the nearest enterable cell within this distance.
    snap_radius_m: float = 0.3
    allow_unknown: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.cost_weight) and self.cost_weight >= 0):
            raise ValueError(f"cost_weight must be a non-negative number, got {self.cost_weight}")
        if not (math.isfinite(self.snap_radius_m) and self.snap_radius_m >= 0):
            raise ValueError(f"snap_radius_m must be a non-negative number, got {self.snap_radius_m}")


@dataclass(frozen=True, eq=False)
class GridPath:
    """A* result: cell centres from start to goal (ends replaced by the exact points when not snapped)."""

    points_xy: np.ndarray
    cells: np.ndarray
    #: Total traversal cost in metres-equivalent (path length when every cell is free).
    cost: float
    expansions: int
    start_snapped: bool
    goal_snapped: bool


def step_multipliers(costs: np.ndarray, cost_weight: float, allow_unknown: bool) -> np.ndarray:
    """Per-cell multiplier of the step length for entering it; 0 marks cells that cannot be entered."""
    costs = np.asarray(costs)
    mult = 1.0 + cost_weight * costs.astype(float) / MAX_NON_OBSTACLE
    unknown = costs == NO_INFORMATION
    mult[unknown] = 1.0 if allow_unknown else 0.0
    mult[(costs >= INSCRIBED_INFLATED_OBSTACLE) & ~unknown] = 0.0
    return mult


class AStarPlanner:
    """Plans on :class:`CostGrid` snapshots; keeps the search arrays of the last grid for reuse."""

    def __init__(self, params: AStarParams | None = None) -> None:
        self.params = params or AStarParams()
        self._prepared_for: CostGrid | None = None
        self._mult: Sequence[float] = array("d")
        self._mult_grid = np.zeros((0, 0))
        self._pad_width = 0

    def plan(self, grid: CostGrid, start_xy: tuple[float, float], goal_xy: tuple[float, float]) -> GridPath:
        """Cheapest 8-connected path from ``start_xy`` to ``goal_xy`` (map frame) on ``grid``."""
        self._prepare(grid)
        start_cell, start_snapped = self._snap(grid, start_xy, "start")
        goal_cell, goal_snapped = self._snap(grid, goal_xy, "goal")
        w = self._pad_width
        start = (start_cell[1] + 1) * w + start_cell[0] + 1
        goal = (goal_cell[1] + 1) * w + goal_cell[0] + 1
        found = search(self._mult, w, start, goal, self._heuristic_to(goal_cell))
        if found is None:
            raise PlanningError(
                f"no path from ({start_xy[0]:.2f}, {start_xy[1]:.2f}) "
                f"to ({goal_xy[0]:.2f}, {goal_xy[1]:.2f}): "
                "the goal is not reachable through free or inflated space"
            )
        flat, cost, expansions = found
        flat_arr = np.asarray(flat, dtype=np.int64)
        cells = np.stack([flat_arr % w - 1, flat_arr // w - 1], axis=1)
        points = grid.frame.cells_to_world(cells)
        if start_snapped:
            points = np.concatenate([np.asarray(start_xy, dtype=float)[None, :], points])
            cells = np.concatenate([np.asarray(grid.frame.world_to_cell(*start_xy))[None, :], cells])
        else:
            points[0] = start_xy
        if not goal_snapped:
            points[-1] = goal_xy
        return GridPath(
            points, cells, cost * grid.frame.resolution_m, expansions, start_snapped, goal_snapped
        )

    def _prepare(self, grid: CostGrid) -> None:
        if self._prepared_for is grid:
            return
        mult = step_multipliers(grid.costs, self.params.cost_weight, self.params.allow_unknown)
        padded = np.zeros((mult.shape[0] + 2, mult.shape[1] + 2))  # a blocked border: no bounds checks
        padded[1:-1, 1:-1] = mult
        self._mult_grid = mult
        self._mult = array("d", padded.tobytes())  # C doubles: built in microseconds, indexed like a list
        self._pad_width = padded.shape[1]
        self._prepared_for = grid

    def _heuristic_to(self, goal_cell: tuple[int, int]) -> Sequence[float]:
        h, w = self._mult_grid.shape
        dx = np.abs(np.arange(-1, w + 1) - goal_cell[0]).astype(float)[None, :]
        dy = np.abs(np.arange(-1, h + 1) - goal_cell[1]).astype(float)[:, None]
        octile = np.maximum(dx, dy) + (_SQRT2 - 1.0) * np.minimum(dx, dy)
        return array("d", octile.tobytes())

    def _snap(self, grid: CostGrid, xy: tuple[float, float], which: str) -> tuple[tuple[int, int], bool]:
        ix, iy = grid.frame.world_to_cell(*xy)
        if not grid.frame.in_bounds(ix, iy):
            raise PlanningError(f"{which} ({xy[0]:.2f}, {xy[1]:.2f}) is outside the map")
        if self._mult_grid[iy, ix] > 0:
            return (ix, iy), False
        reach = int(math.floor(self.params.snap_radius_m / grid.frame.resolution_m + 1e-9))
        h, w = self._mult_grid.shape
        y0, y1, x0, x1 = (
            max(0, iy - reach),
            min(h, iy + reach + 1),
            max(0, ix - reach),
            min(w, ix + reach + 1),
        )
        ys, xs = np.mgrid[y0:y1, x0:x1]
        d2 = (xs - ix) ** 2 + (ys - iy) ** 2
        ok = (self._mult_grid[y0:y1, x0:x1] > 0) & (d2 <= reach * reach)
        if not ok.any():
            cost = grid.costs[iy, ix]
            what = (
                "unknown space"
                if cost == NO_INFORMATION
                else f"an obstacle or its inscribed zone (cost {cost})"
            )
            raise PlanningError(
                f"{which} ({xy[0]:.2f}, {xy[1]:.2f}) is in {what} and no free cell lies within "
                f"{self.params.snap_radius_m:.2f} m"
            )
        # Nearest first, then cheapest.
        order = np.lexsort((grid.costs[y0:y1, x0:x1][ok], d2[ok]))
        return (int(xs[ok][order[0]]), int(ys[ok][order[0]])), True


def search(
    mult: Sequence[float], width: int, start: int, goal: int, heuristic: Sequence[float]
) -> tuple[list[int], float, int] | None:
    """A* over a flat, padded grid (border cells have multiplier 0) in cell units.

    Returns ``(flat cell indices from start to goal, cost, expansions)`` or ``None`` if unreachable.
    Ties on ``f`` go to the node nearer the goal, which keeps open-field searches narrow. Closed
    neighbours need no check: with a consistent heuristic their ``g`` is already optimal, and every step
    costs at least one cell, so a relaxation can never lower it (nor loop a parent back).
    """
    if mult[start] <= 0 or mult[goal] <= 0:
        return None
    n = len(mult)
    g = [math.inf] * n
    parent = [-1] * n
    closed = bytearray(n)
    g[start] = 0.0
    straight = (1, -1, width, -width)
    diagonals = (
        (width + 1, 1, width),
        (width - 1, -1, width),
        (-width + 1, 1, -width),
        (-width - 1, -1, -width),
    )
    heap: list[tuple[float, float, int]] = [(heuristic[start], heuristic[start], start)]
    push, pop = heapq.heappush, heapq.heappop
    expansions = 0
    while heap:
        _, _, u = pop(heap)
        if closed[u]:
            continue
        if u == goal:
            path = [u]
            while u != start:
                u = parent[u]
                path.append(u)
            path.reverse()
            return path, g[goal], expansions
        closed[u] = 1
        expansions += 1
        gu = g[u]
        for off in straight:
            v = u + off
            m = mult[v]
            if m > 0.0:
                ng = gu + m
                if ng < g[v]:
                    g[v] = ng
                    parent[v] = u
                    hv = heuristic[v]
                    push(heap, (ng + hv, hv, v))
        for off, side_a, side_b in diagonals:
            v = u + off
            m = mult[v]
            if m > 0.0 and mult[u + side_a] > 0.0 and mult[u + side_b] > 0.0:
                ng = gu + _SQRT2 * m
                if ng < g[v]:
                    g[v] = ng
                    parent[v] = u
                    hv = heuristic[v]
                    push(heap, (ng + hv, hv, v))
    return None
