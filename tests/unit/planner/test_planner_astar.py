"""A*: optimal against a brute-force Dijkstra on random grids, never enters blocked cells, snaps ends."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest

from services.planner.astar import AStarParams, AStarPlanner, PlanningError
from services.planner.costmap import INSCRIBED_INFLATED_OBSTACLE, LETHAL_OBSTACLE, NO_INFORMATION, CostGrid
from services.planner.grid_frame import GridFrame

RES = 0.05


def _grid(costs: np.ndarray) -> CostGrid:
    costs = np.asarray(costs, dtype=np.uint8)
    return CostGrid(GridFrame(RES, (0.0, 0.0, 0.0), costs.shape[1], costs.shape[0]), costs)


def _centre(ix: int, iy: int) -> tuple[float, float]:
    return ((ix + 0.5) * RES, (iy + 0.5) * RES)


def _enterable(cost: int, allow_unknown: bool) -> bool:
    return cost < INSCRIBED_INFLATED_OBSTACLE or (allow_unknown and cost == NO_INFORMATION)


def _step_cost(
    costs: np.ndarray, a: tuple[int, int], b: tuple[int, int], weight: float, allow_unknown: bool
) -> float | None:
    """Cost in cells of one 8-connected step a -> b (ix, iy), or None when the step is not allowed."""
    (ax, ay), (bx, by) = a, b
    h, w = costs.shape
    if not (0 <= bx < w and 0 <= by < h) or max(abs(bx - ax), abs(by - ay)) != 1:
        return None
    if not _enterable(int(costs[by, bx]), allow_unknown):
        return None
    if (
        ax != bx
        and ay != by
        and not (
            _enterable(int(costs[ay, bx]), allow_unknown) and _enterable(int(costs[by, ax]), allow_unknown)
        )
    ):
        return None
    cost = 0 if costs[by, bx] == NO_INFORMATION else int(costs[by, bx])
    return math.hypot(bx - ax, by - ay) * (1.0 + weight * cost / 252.0)


def _dijkstra(
    costs: np.ndarray, start: tuple[int, int], goal: tuple[int, int], weight: float, allow_unknown: bool
) -> float:
    """Plain Dijkstra over every cell; infinity when unreachable."""
    best = {start: 0.0}
    queue = [(0.0, start)]
    done = set()
    while queue:
        d, cell = heapq.heappop(queue)
        if cell in done:
            continue
        if cell == goal:
            return d
        done.add(cell)
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                nxt = (cell[0] + dx, cell[1] + dy)
                step = _step_cost(costs, cell, nxt, weight, allow_unknown)
                if step is not None and d + step < best.get(nxt, math.inf):
                    best[nxt] = d + step
                    heapq.heappush(queue, (d + step, nxt))
    return math.inf


def _random_costs(rng: np.random.Generator) -> np.ndarray:
    h, w = (int(v) for v in rng.integers(3, 16, 2))
    costs = rng.integers(0, 253, (h, w))
    costs[rng.random((h, w)) < 0.4] = 0
    blocked = rng.random((h, w)) < rng.uniform(0.0, 0.35)
    costs[blocked] = rng.choice([INSCRIBED_INFLATED_OBSTACLE, LETHAL_OBSTACLE, NO_INFORMATION], blocked.sum())
    return costs.astype(np.uint8)


@pytest.mark.parametrize("seed", range(6))
def test_astar_is_optimal_against_brute_force_dijkstra(seed: int) -> None:
    rng = np.random.default_rng(seed)
    checked = 0
    for _ in range(25):
        costs = _random_costs(rng)
        h, w = costs.shape
        weight = float(rng.choice([0.0, 1.0, 3.0, 10.0]))
        allow_unknown = bool(rng.random() < 0.3)
        free = [(x, y) for y in range(h) for x in range(w) if _enterable(int(costs[y, x]), allow_unknown)]
        if len(free) < 2:
            continue
        start, goal = (free[i] for i in rng.choice(len(free), 2, replace=False))
        expected = _dijkstra(costs, start, goal, weight, allow_unknown)
        planner = AStarPlanner(
            AStarParams(cost_weight=weight, allow_unknown=allow_unknown, snap_radius_m=0.0)
        )
        if math.isinf(expected):
            with pytest.raises(PlanningError, match="no path"):
                planner.plan(_grid(costs), _centre(*start), _centre(*goal))
            continue
        found = planner.plan(_grid(costs), _centre(*start), _centre(*goal))
        cells = [tuple(int(v) for v in c) for c in found.cells]
        assert cells[0] == start and cells[-1] == goal
        walked = 0.0
        for a, b in zip(cells[:-1], cells[1:], strict=True):
            step = _step_cost(costs, a, b, weight, allow_unknown)
            assert step is not None, f"illegal step {a} -> {b}"
            walked += step
        assert found.cost / RES == pytest.approx(walked, rel=1e-9)
        assert walked == pytest.approx(expected, rel=1e-9)
        checked += 1
    assert checked >= 10


def test_never_cuts_a_corner_between_blocked_cells() -> None:
    costs = np.zeros((3, 3), dtype=np.uint8)
    costs[0, 1] = LETHAL_OBSTACLE
    costs[1, 0] = LETHAL_OBSTACLE
    with pytest.raises(PlanningError, match="no path"):
        AStarPlanner(AStarParams(snap_radius_m=0.0)).plan(_grid(costs), _centre(2, 2), _centre(0, 0))


def test_path_keeps_away_from_cost_when_weighted() -> None:
    costs = np.zeros((9, 20), dtype=np.uint8)
    costs[4, 3:17] = 200  # an expensive band along the straight line
    straight = AStarPlanner(AStarParams(cost_weight=0.0)).plan(_grid(costs), _centre(1, 4), _centre(18, 4))
    weighted = AStarPlanner(AStarParams(cost_weight=3.0)).plan(_grid(costs), _centre(1, 4), _centre(18, 4))
    assert (straight.cells[:, 1] == 4).all()
    assert not (weighted.cells[3:-3, 1] == 4).any()


def test_exact_ends_replace_cell_centres() -> None:
    found = AStarPlanner().plan(_grid(np.zeros((10, 10))), (0.012, 0.031), (0.41, 0.22))
    assert found.points_xy[0] == pytest.approx((0.012, 0.031))
    assert found.points_xy[-1] == pytest.approx((0.41, 0.22))
    assert not found.start_snapped and not found.goal_snapped


def test_blocked_ends_snap_to_the_nearest_free_cell() -> None:
    costs = np.zeros((20, 20), dtype=np.uint8)
    costs[8:12, 8:12] = INSCRIBED_INFLATED_OBSTACLE
    costs[10, 10] = LETHAL_OBSTACLE
    found = AStarPlanner(AStarParams(snap_radius_m=0.15)).plan(_grid(costs), _centre(10, 10), _centre(1, 1))
    assert found.start_snapped and not found.goal_snapped
    assert found.points_xy[0] == pytest.approx(_centre(10, 10))  # the path still starts at the robot
    first_free = tuple(found.cells[1])
    assert math.dist(first_free, (10, 10)) == pytest.approx(2.0)
    assert costs[first_free[1], first_free[0]] == 0


def test_clear_errors_when_ends_cannot_be_used() -> None:
    costs = np.zeros((20, 20), dtype=np.uint8)
    costs[5:15, 5:15] = LETHAL_OBSTACLE
    planner = AStarPlanner(AStarParams(snap_radius_m=0.1))
    with pytest.raises(PlanningError, match=r"goal \(0\.50, 0\.50\) is in an obstacle .*cost 254.* 0\.10 m"):
        planner.plan(_grid(costs), _centre(1, 1), (0.5, 0.5))
    with pytest.raises(PlanningError, match="start .* is outside the map"):
        planner.plan(_grid(costs), (-1.0, 0.2), _centre(1, 1))
    costs[:, :] = NO_INFORMATION
    costs[0, 0] = 0
    with pytest.raises(PlanningError, match="unknown space"):
        planner.plan(_grid(costs), _centre(0, 0), _centre(10, 10))


def test_unknown_cells_only_when_allowed() -> None:
    costs = np.zeros((5, 12), dtype=np.uint8)
    costs[:, 5] = NO_INFORMATION
    with pytest.raises(PlanningError, match="no path"):
        AStarPlanner().plan(_grid(costs), _centre(1, 2), _centre(10, 2))
    found = AStarPlanner(AStarParams(allow_unknown=True)).plan(_grid(costs), _centre(1, 2), _centre(10, 2))
    assert found.cost == pytest.approx(9 * RES)


def test_params_are_validated() -> None:
    with pytest.raises(ValueError, match="cost_weight"):
        AStarParams(cost_weight=-1.0)
    with pytest.raises(ValueError, match="snap_radius_m"):
        AStarParams(snap_radius_m=math.nan)
