"""Smoothing: shortcuts and smoothing never cross costly cells, spacing and orientations are right."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from services.planner.astar import AStarPlanner, PlanningError
from services.planner.bench import bench_planning
from services.planner.costmap import INSCRIBED_INFLATED_OBSTACLE, CostGrid, LayeredCostmap
from services.planner.global_planner import GlobalPlanner, GlobalPlannerParams
from services.planner.grid_frame import GridFrame
from services.planner.grid_lines import segment_cells
from services.planner.occupancy_map import OCC_FREE, OCC_OCCUPIED, OccupancyMap
from services.planner.rasterize import map_from_world
from services.planner.smoothing import (
    SmoothingParams,
    gradient_smooth,
    orientations,
    resample_path,
    shortcut_path,
    smooth_path,
)
from shared.world import load_world

WORLDS = Path(__file__).resolve().parents[3] / "deploy" / "worlds"


def _random_obstacle_costmap(rng: np.random.Generator, size: int = 80) -> CostGrid:
    data = np.full((size, size), OCC_FREE, dtype=np.int8)
    data[[0, -1], :] = OCC_OCCUPIED
    data[:, [0, -1]] = OCC_OCCUPIED
    for _ in range(int(rng.integers(4, 12))):
        x, y = (int(v) for v in rng.integers(5, size - 5, 2))
        w, h = (int(v) for v in rng.integers(1, 12, 2))
        data[y : y + h, x : x + w] = OCC_OCCUPIED
    return LayeredCostmap(OccupancyMap(0.05, (0.0, 0.0, 0.0), data)).grid()


def _max_cost_crossed(grid: CostGrid, poses: np.ndarray) -> int:
    """Highest cost of any cell the polyline passes through (exact supercover of every segment)."""
    worst = 0
    grid_xy = grid.frame.world_to_grid(poses[:, :2])
    for a, b in zip(grid_xy[:-1], grid_xy[1:], strict=True):
        cells = segment_cells(a, b)
        worst = max(worst, int(grid.costs[cells[:, 1], cells[:, 0]].max()))
    return worst


def _weighted_cost(grid: CostGrid, points: np.ndarray, weight: float = 3.0) -> float:
    """A*'s traversal cost of a polyline, integrated in steps of a quarter cell."""
    total = 0.0
    for a, b in zip(points[:-1], points[1:], strict=True):
        n = max(1, math.ceil(math.dist(a, b) / 0.0125))
        samples = a + (b - a) * (np.arange(n)[:, None] / n)
        total += float(np.sum(math.dist(a, b) / n * (1.0 + weight * grid.costs_at(samples) / 252.0)))
    return total


def test_smoothed_paths_never_cross_inscribed_or_lethal_cells() -> None:
    rng = np.random.default_rng(5)
    planner = GlobalPlanner()
    planned = 0
    for _ in range(12):
        grid = _random_obstacle_costmap(rng)
        free = np.argwhere(grid.costs == 0)
        start, goal = (grid.frame.cell_to_world(int(c[1]), int(c[0])) for c in free[rng.choice(len(free), 2)])
        try:
            path = planner.compute_path(grid, (*start, 0.0), (*goal, 1.0))
        except PlanningError:
            continue
        planned += 1
        raw_worst = int(grid.costs_at(path.grid_points).max())
        worst = _max_cost_crossed(grid, path.poses)
        assert worst < INSCRIBED_INFLATED_OBSTACLE
        assert worst <= max(SmoothingParams().max_cost, raw_worst)
    assert planned >= 6


def test_shortcuts_never_cut_through_a_thin_wall() -> None:
    # A one-cell wall with its opening far to the side: crossing it would be much shorter.
    rng = np.random.default_rng(8)
    for _ in range(4):
        data = np.full((60, 60), OCC_FREE, dtype=np.int8)
        row = int(rng.integers(20, 40))
        data[row, :] = OCC_OCCUPIED
        gap = int(rng.choice([2, 44]))
        data[row, gap : gap + 14] = OCC_FREE
        grid = LayeredCostmap(OccupancyMap(0.05, (0.0, 0.0, 0.0), data)).grid()
        x = float(rng.uniform(1.2, 1.8))
        # Unweighted shortcutting: only the line-of-sight check stands between the path and the wall.
        unweighted = GlobalPlannerParams(smoothing=SmoothingParams(cost_weight=0.0))
        path = GlobalPlanner(unweighted).compute_path(grid, (x, 0.3, 0.0), (3.0 - x, 2.7, 0.0))
        assert _max_cost_crossed(grid, path.poses) < INSCRIBED_INFLATED_OBSTACLE


def test_smoothing_is_undone_where_it_would_cut_into_cost() -> None:
    data = np.full((60, 60), OCC_FREE, dtype=np.int8)
    data[21:40, 18:29] = OCC_OCCUPIED  # x in [0.9, 1.45], y in [1.05, 2.0]
    grid = LayeredCostmap(OccupancyMap(0.05, (0.0, 0.0, 0.0), data)).grid()
    corner = np.array([[0.3, 0.75], [1.75, 0.75], [1.75, 2.5]])  # 0.3 m clear of the block (cost 160)
    strong = SmoothingParams(max_cost=170, data_weight=0.02, smooth_weight=0.45, iterations=200)
    unsmoothed = resample_path(corner, 0.05)
    # Unchecked, this much smoothing cuts the corner into costlier cells.
    assert _max_cost_crossed(grid, gradient_smooth(unsmoothed, 0.02, 0.45, 200)) > 170
    poses = smooth_path(grid, corner, params=strong)
    assert _max_cost_crossed(grid, corner) <= 170
    assert _max_cost_crossed(grid, poses) <= 170
    assert len(poses) == len(unsmoothed)
    assert np.hypot(*np.diff(poses[:, :2], axis=0).T).max() < 0.06  # put back without kinks


def test_shortcuts_straighten_a_staircase_in_open_space() -> None:
    grid = CostGrid(GridFrame(0.05, (0.0, 0.0, 0.0), 60, 60), np.zeros((60, 60), dtype=np.uint8))
    found = AStarPlanner().plan(grid, (0.1, 0.1), (2.8, 1.3))
    kept = shortcut_path(grid, found.points_xy)
    assert len(found.points_xy) > 30
    np.testing.assert_allclose(kept, [[0.1, 0.1], [2.8, 1.3]])


def test_shortcuts_do_not_pull_the_path_towards_obstacles() -> None:
    data = np.full((60, 80), OCC_FREE, dtype=np.int8)
    data[0:34, 38:42] = OCC_OCCUPIED  # a wall to go around, its end at y = 1.7 m
    grid = LayeredCostmap(OccupancyMap(0.05, (0.0, 0.0, 0.0), data)).grid()
    found = AStarPlanner().plan(grid, (0.5, 0.5), (3.5, 0.5))
    tight = shortcut_path(grid, found.points_xy, SmoothingParams(max_cost=252, cost_weight=0.0))
    careful = shortcut_path(grid, found.points_xy, SmoothingParams(max_cost=252, cost_weight=3.0))
    # Ignoring cost, the shortcut grazes the wall's inflation; weighted, it only cuts where that is cheaper.
    assert _max_cost_crossed(grid, tight) > _max_cost_crossed(grid, careful)
    assert _weighted_cost(grid, careful) <= _weighted_cost(grid, found.points_xy) + 0.025 * len(careful)
    assert _weighted_cost(grid, careful) < _weighted_cost(grid, tight)


def test_resampling_and_orientations() -> None:
    dense = resample_path(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.52]]), 0.05)
    steps = np.hypot(*np.diff(dense, axis=0).T)
    assert steps.max() <= 0.05 + 1e-9 and steps.min() > 0.03  # the shortest step cuts the corner
    assert dense[0] == pytest.approx([0.0, 0.0]) and dense[-1] == pytest.approx([1.0, 0.52])
    yaw = orientations(dense, goal_yaw_rad=0.3)
    assert yaw[0] == pytest.approx(0.0) and yaw[-1] == pytest.approx(0.3)
    assert yaw[-2] == pytest.approx(math.pi / 2)


def test_smooth_path_returns_poses_spaced_about_five_centimetres() -> None:
    grid = CostGrid(GridFrame(0.05, (0.0, 0.0, 0.0), 60, 60), np.zeros((60, 60), dtype=np.uint8))
    poses = smooth_path(grid, np.array([[0.2, 0.2], [1.5, 0.2], [1.5, 2.5]]), goal_yaw_rad=-1.0)
    steps = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    assert poses.shape[1] == 3 and steps.max() < 0.06 and steps.min() > 0.03
    assert poses[-1] == pytest.approx([1.5, 2.5, -1.0])
    # The corner is rounded: no point sits exactly on it any more.
    assert np.min(np.hypot(poses[:, 0] - 1.5, poses[:, 1] - 0.2)) > 0.01


def test_global_planner_in_the_seed_room() -> None:
    world = load_world(WORLDS / "seed_room.yaml")
    grid = LayeredCostmap(map_from_world(world)).grid()
    path = GlobalPlanner().compute_path(grid, world.robot.start, (0.0, 2.0, -math.pi / 2))
    assert path.poses[0, :2] == pytest.approx(world.robot.start[:2])
    assert path.poses[-1] == pytest.approx([0.0, 2.0, -math.pi / 2])
    assert path.search_resolution_m == 0.05
    straight = math.dist(world.robot.start[:2], (0.0, 2.0))
    assert straight <= path.length_m < 1.15 * straight
    assert _max_cost_crossed(grid, path.poses) < INSCRIBED_INFLATED_OBSTACLE


def test_large_grids_are_searched_at_half_resolution() -> None:
    world = load_world(WORLDS / "seed_room.yaml")
    grid = LayeredCostmap(map_from_world(world)).grid()
    params = GlobalPlannerParams(max_full_resolution_cells=1000)
    path = GlobalPlanner(params).compute_path(grid, world.robot.start, (-1.0, 1.4, -math.pi / 2))
    assert path.search_resolution_m == pytest.approx(0.1)
    assert np.hypot(*np.diff(path.poses[:, :2], axis=0).T).max() < 0.06
    assert _max_cost_crossed(grid, path.poses) < INSCRIBED_INFLATED_OBSTACLE


def test_bench_reports_medians() -> None:
    result = bench_planning(repeats=1, resolution_m=0.1)
    assert (result["grid_width"], result["grid_height"]) == (200.0, 200.0)
    for key in ("inflation_ms", "astar_ms", "plan_ms", "plan_full_resolution_ms"):
        assert 0.0 < result[key] < 5000.0
    assert result["path_length_m"] > 15.0


def _gap_room(detour_wall_to_m: float) -> CostGrid:
    """A wall across a 4 m room at y = 0 with a 0.4 m gap at x = 0 (only the inscribed circle fits), and
    open floor past the wall's east end at ``detour_wall_to_m``."""
    n = 80  # 0.05 m cells, origin (-2, -2)
    data = np.full((n, n), OCC_FREE, dtype=np.int8)
    wall_row = 40
    for ix in range(n):
        x = -2.0 + (ix + 0.5) * 0.05
        if abs(x) > 0.2 and x < detour_wall_to_m:
            data[wall_row, ix] = OCC_OCCUPIED
    return LayeredCostmap(OccupancyMap(0.05, (-2.0, -2.0, 0.0), data)).grid()


def _min_clearance_cost_on(grid: CostGrid, path_poses: np.ndarray) -> int:
    return int(grid.costs_at(path_poses[:, :2]).max())


def test_a_gap_only_the_inscribed_circle_fits_is_avoided_when_a_fair_detour_exists() -> None:
    grid = _gap_room(detour_wall_to_m=0.9)  # open past x = 0.9: a detour under twice the length
    params = GlobalPlannerParams(preferred_clearance_cost=186)
    through_gap = GlobalPlanner().compute_path(grid, (0.0, -1.0, math.pi / 2), (0.0, 1.0, math.pi / 2))
    roomy = GlobalPlanner(params).compute_path(grid, (0.0, -1.0, math.pi / 2), (0.0, 1.0, math.pi / 2))
    assert _min_clearance_cost_on(grid, through_gap.poses) >= 186  # squeezes through the gap
    assert _min_clearance_cost_on(grid, roomy.poses) < 186  # goes round the wall's end instead
    assert roomy.length_m > through_gap.length_m


def test_the_gap_is_still_taken_when_the_way_round_is_too_long_or_missing() -> None:
    params = GlobalPlannerParams(preferred_clearance_cost=186)
    closed = _gap_room(detour_wall_to_m=9.0)  # no way round at all
    path = GlobalPlanner(params).compute_path(closed, (0.0, -1.0, math.pi / 2), (0.0, 1.0, math.pi / 2))
    assert _min_clearance_cost_on(closed, path.poses) >= 186
    short_hop = GlobalPlanner(params).compute_path(
        _gap_room(detour_wall_to_m=0.8), (0.0, -0.4, math.pi / 2), (0.0, 0.4, math.pi / 2)
    )
    assert short_hop.length_m < 1.2  # 0.8 m through the gap beats a detour of several metres
