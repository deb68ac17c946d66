"""Layered costmap: exact distance transform, Nav2 inflation values, lidar raytracing, sonar cones."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from services.planner.bench import bench_world
from services.planner.costmap import (
    FREE_SPACE,
    INSCRIBED_INFLATED_OBSTACLE,
    LETHAL_OBSTACLE,
    NO_INFORMATION,
    CostmapParams,
    LayeredCostmap,
    inflate,
    laser_scan_points,
    occupancy_from_costs,
)
from services.planner.distance_transform import distance_to_marks
from services.planner.glass_memory import GlassMemory
from services.planner.global_planner import GlobalPlanner
from services.planner.occupancy_map import OCC_FREE, OCC_OCCUPIED, OCC_UNKNOWN, OccupancyMap
from services.planner.rasterize import map_from_world
from shared.world import load_world

WORLDS = Path(__file__).resolve().parents[3] / "deploy" / "worlds"


def _free_map(width: int = 60, height: int = 60, resolution_m: float = 0.05) -> OccupancyMap:
    return OccupancyMap(resolution_m, (0.0, 0.0, 0.0), np.full((height, width), OCC_FREE, dtype=np.int8))


def _nav2_cost(distance_m: float, inscribed_m: float, scaling: float, inflation_m: float) -> int:
    """Nav2 InflationLayer::computeCost, written out independently of the module under test."""
    if distance_m == 0.0:
        return 254
    if distance_m <= inscribed_m + 1e-9:
        return 253
    if distance_m > inflation_m + 1e-9:
        return 0
    return int(252 * math.exp(-scaling * (distance_m - inscribed_m)))


def test_distance_transform_matches_brute_force() -> None:
    rng = np.random.default_rng(11)
    for _ in range(40):
        h, w = (int(v) for v in rng.integers(1, 25, 2))
        marks = rng.random((h, w)) < rng.random() * 0.15
        cutoff = float(rng.random() * 14)
        got = distance_to_marks(marks, cutoff)
        ys, xs = np.nonzero(marks)
        iy, ix = np.mgrid[0:h, 0:w]
        if len(ys):
            expected = np.sqrt(((iy[..., None] - ys) ** 2 + (ix[..., None] - xs) ** 2).min(axis=-1))
        else:
            expected = np.full((h, w), np.inf)
        expected[expected > cutoff] = np.inf
        np.testing.assert_array_equal(got, expected)


def test_distance_transform_of_a_few_marks_in_a_large_grid_matches_brute_force() -> None:
    """Only the marks' surroundings are computed; every cell still gets its exact distance (or far)."""
    rng = np.random.default_rng(12)
    for _ in range(40):
        h, w = (int(v) for v in rng.integers(20, 90, 2))
        marks = np.zeros((h, w), dtype=bool)
        for _ in range(int(rng.integers(1, 5))):
            marks[int(rng.integers(0, h)), int(rng.integers(0, w))] = True
        cutoff = float(rng.random() * 9)
        got = distance_to_marks(marks, cutoff)
        ys, xs = np.nonzero(marks)
        iy, ix = np.mgrid[0:h, 0:w]
        expected = np.sqrt(((iy[..., None] - ys) ** 2 + (ix[..., None] - xs) ** 2).min(axis=-1))
        expected[expected > cutoff] = np.inf
        np.testing.assert_array_equal(got, expected)


def test_inflation_values_match_nav2_formula_at_known_distances() -> None:
    params = CostmapParams(inflation_radius_m=0.55, cost_scaling_factor=3.0)
    assert params.inscribed_radius_m == pytest.approx(0.15)
    grid_map = _free_map()
    grid_map.data[30, 30] = OCC_OCCUPIED
    costs = LayeredCostmap(grid_map, params).grid().costs
    seen = set()
    for dx, dy in [
        (0, 0),
        (1, 0),
        (2, 2),
        (3, 0),
        (0, 4),
        (3, 4),
        (6, 0),
        (5, 5),
        (8, 6),
        (11, 0),
        (8, 8),
        (12, 0),
    ]:
        d = math.hypot(dx, dy) * 0.05
        expected = _nav2_cost(d, 0.15, 3.0, 0.55)
        assert costs[30 + dy, 30 + dx] == expected, (dx, dy, d)
        assert costs[30 - dy, 30 - dx] == expected
        seen.add(expected)
    # The sample covers every regime: lethal, inscribed, decaying, beyond the radius.
    assert {254, 253, 0} <= seen and len(seen) >= 7
    assert costs[30 + 4, 30 + 3] == int(252 * math.exp(-3.0 * 0.1))  # d = 0.25 m


def test_inflation_keeps_unknown_except_inside_the_inscribed_radius() -> None:
    grid_map = _free_map(20, 5)
    grid_map.data[:, 10:] = OCC_UNKNOWN
    grid_map.data[2, 9] = OCC_OCCUPIED
    costs = LayeredCostmap(grid_map).grid().costs
    assert costs[2, 10] == INSCRIBED_INFLATED_OBSTACLE  # unknown, 1 cell from lethal
    assert costs[2, 15] == NO_INFORMATION
    assert 0 < costs[2, 4] < INSCRIBED_INFLATED_OBSTACLE


def test_inflation_of_a_400_by_400_grid_is_fast() -> None:
    import time

    grid_map = map_from_world(bench_world(), resolution_m=0.05, padding_m=0.0)
    assert (grid_map.width, grid_map.height) == (400, 400)
    costmap = LayeredCostmap(grid_map)
    times = []
    for _ in range(5):
        costmap.clear()
        t0 = time.perf_counter()
        costmap.grid()
        times.append(time.perf_counter() - t0)
    assert sorted(times)[2] < 0.05


def test_scan_marks_hits_and_clears_along_beams() -> None:
    grid_map = _free_map()
    grid_map.data[:, 40:] = OCC_UNKNOWN  # unmapped space the beams will reveal
    costmap = LayeredCostmap(grid_map, CostmapParams(obstacle_max_range_m=2.0, raytrace_max_range_m=2.5))
    sensor = (0.5, 1.5)
    endpoints = np.array([[2.5, 1.5], [0.5, 0.25], [2.4, 2.6]])
    costmap.update_with_scan(sensor, endpoints)
    layer = costmap.obstacle_layer
    assert layer[30, 50] == LETHAL_OBSTACLE  # hit at 2.0 m, inside obstacle_max_range
    assert layer[5, 10] == LETHAL_OBSTACLE
    # The 2.19 m beam hit beyond the marking range: its way is cleared, its end cell left as it was.
    assert layer[52, 48] == NO_INFORMATION
    assert layer[51, 46] == FREE_SPACE
    assert np.all(layer[30, 10:50] == FREE_SPACE)  # the beam cleared its way, through unknown too
    costs = costmap.grid().costs
    assert costs[30, 45] < INSCRIBED_INFLATED_OBSTACLE  # unknown became known free
    assert costs[30, 50] == LETHAL_OBSTACLE


def test_scan_clears_old_marks_but_never_static_walls() -> None:
    grid_map = _free_map()
    grid_map.data[30, 30] = OCC_OCCUPIED
    costmap = LayeredCostmap(grid_map)
    costmap.update_with_scan((0.5, 1.5), np.array([[1.0, 1.5]]))
    assert costmap.grid().costs[30, 20] == LETHAL_OBSTACLE
    # A longer beam along the same line sees past the old obstacle (it moved) and through the wall cell.
    costmap.update_with_scan((0.5, 1.5), np.array([[2.0, 1.5]]), hits=np.array([False]))
    costs = costmap.grid().costs
    assert costmap.obstacle_layer[30, 20] == FREE_SPACE
    assert costs[30, 20] == int(252 * math.exp(-3.0 * (0.5 - 0.15)))  # only the wall's inflation is left
    assert costs[30, 30] == LETHAL_OBSTACLE


def test_raytrace_range_limits_clearing() -> None:
    costmap = LayeredCostmap(_free_map(), CostmapParams(raytrace_max_range_m=1.0))
    costmap.update_with_scan((0.1, 0.1), np.array([[2.9, 0.1]]), hits=np.array([False]))
    layer = costmap.obstacle_layer
    assert layer[2, 21] == FREE_SPACE  # 1.0 m out
    assert layer[2, 24] == NO_INFORMATION  # beyond the raytrace range


def test_laser_scan_points_handles_inf_nan_and_limits() -> None:
    ranges = np.array([1.0, np.inf, np.nan, 0.01, 12.0, -np.inf])
    endpoints, hits = laser_scan_points((1.0, 2.0, math.pi / 2), 0.0, math.pi / 2, ranges, 0.05, 10.0)
    # Kept: 1.0 (hit, straight ahead = +y), inf (no return, at range_max), 12.0 (>= range_max, no return).
    assert hits.tolist() == [True, False, False]
    np.testing.assert_allclose(endpoints[0], [1.0, 3.0], atol=1e-12)
    np.testing.assert_allclose(endpoints[1], [-9.0, 2.0], atol=1e-9)  # 90 degrees further: -x


def test_lidar_does_not_clear_glass_in_the_static_layer() -> None:
    glass_map = _free_map()
    glass_map.data[30, 25:35] = OCC_OCCUPIED  # glass memory folded into the static map
    costmap = LayeredCostmap(glass_map)
    costmap.update_with_scan((1.5, 0.5), np.array([[1.5, 2.9]]), hits=np.array([False]))  # lidar sees through
    assert costmap.grid().costs[30, 30] == LETHAL_OBSTACLE


def test_clear_resets_dynamic_layers_and_footprint_clearing() -> None:
    grid_map = _free_map()
    grid_map.data[5, 5] = OCC_OCCUPIED
    costmap = LayeredCostmap(grid_map)
    costmap.update_with_scan((0.5, 1.5), np.array([[1.0, 1.5], [0.5, 2.0]]))
    costmap.clear_footprint((0.5, 2.0, 0.0))
    assert costmap.obstacle_layer[40, 10] == FREE_SPACE
    assert costmap.obstacle_layer[30, 20] == LETHAL_OBSTACLE
    snapshot = costmap.grid()
    assert costmap.grid() is snapshot  # cached until something changes
    costmap.clear()
    assert costmap.grid() is not snapshot
    assert np.all(costmap.obstacle_layer == NO_INFORMATION)
    costs = costmap.grid().costs
    assert costs[30, 20] == FREE_SPACE and costs[30, 30] == FREE_SPACE
    assert costs[5, 5] == LETHAL_OBSTACLE


def test_footprint_costs_see_the_outline_and_the_map_edge() -> None:
    grid_map = _free_map()
    grid_map.data[30, 34] = OCC_OCCUPIED  # x = 1.725
    grid = LayeredCostmap(grid_map, CostmapParams(inflation_radius_m=0.0)).grid()
    # Facing +x at x = 1.525 the front edge (x + 0.2) lies on the obstacle; turned 90 degrees it does not.
    costs = grid.footprint_costs(
        np.array([[1.525, 1.525, 0.0], [1.525, 1.525, math.pi / 2], [0.1, 1.5, 0.0]])
    )
    assert costs.tolist() == [LETHAL_OBSTACLE, FREE_SPACE, LETHAL_OBSTACLE]


def test_occupancy_translation_for_display() -> None:
    values = occupancy_from_costs(np.array([0, 1, 128, 252, 253, 254, 255], dtype=np.uint8))
    assert values.tolist() == [0, 1, 1 + (97 * 127) // 251, 98, 99, 100, -1]


def test_glass_enters_through_the_sonar_and_the_planner_goes_around() -> None:
    world = load_world(WORLDS / "glass_room.yaml")
    base = map_from_world(world)
    costmap = LayeredCostmap(base)
    glass = GlassMemory(base.frame, costmap.params, suspicion_radius_m=0.0)
    start, goal = world.robot.start, (-1.0, 1.4, -math.pi / 2)
    planner = GlobalPlanner()

    def crossing_x(poses: np.ndarray) -> float:
        i = int(np.nonzero(poses[:, 1] < 2.6)[0][0])
        return float(poses[i, 0])

    before = planner.compute_path(costmap.grid(), start, goal)
    assert -1.9 < crossing_x(before.poses) < 1.6  # straight through the glass
    (gx1, gy), (gx2, _) = world.glass[0]
    for x in np.arange(gx1, gx2 + 0.01, 0.1):  # the robot's sonar sweeping along the pane
        glass.add_reading((float(x), gy + 0.8, -math.pi / 2), 0.8, 0.26, 0.02, 3.0)
    data = base.data.copy()
    data[glass.glass_mask()] = OCC_OCCUPIED  # as the planner folds glass into the static layer
    costmap.set_static_map(OccupancyMap(base.resolution_m, base.origin, data))
    costs = costmap.grid()
    after = planner.compute_path(costs, start, goal)
    assert crossing_x(after.poses) > 1.6  # through the opening at the end of the glass
    assert costs.costs_at(after.poses[:, :2]).max() < INSCRIBED_INFLATED_OBSTACLE


@pytest.mark.parametrize("seed", range(4))
def test_inflating_round_the_changes_gives_the_whole_grid_inflated_anew(seed: int) -> None:
    """Scans, clearing, a new static layer (glass) and new settings: each snapshot is exactly the one a
    full inflation of the combined layers gives, and a scan that changes nothing keeps the snapshot."""
    rng = np.random.default_rng(seed)
    data = np.full((70, 90), OCC_FREE, dtype=np.int8)
    data[rng.random(data.shape) < 0.01] = OCC_OCCUPIED
    data[:, :3] = OCC_UNKNOWN
    static = OccupancyMap(0.05, (0.0, 0.0, 0.0), data)
    costmap = LayeredCostmap(static, CostmapParams())
    for step in range(40):
        kind = rng.integers(0, 10)
        scan = None
        if kind < 6:
            sensor = rng.uniform([0.3, 0.3], [4.2, 3.2])
            angles = rng.uniform(-math.pi, math.pi, 30)
            ranges = rng.uniform(0.2, 2.0, 30)
            ends = sensor + np.stack([ranges * np.cos(angles), ranges * np.sin(angles)], axis=1)
            scan = ((float(sensor[0]), float(sensor[1])), ends, rng.random(30) < 0.7)
            costmap.update_with_scan(*scan)
        elif kind < 7:
            costmap.clear_around((float(rng.uniform(0, 4.5)), float(rng.uniform(0, 3.5))), 0.4)
        elif kind < 8:
            glass = data.copy()
            row = int(rng.integers(0, 70))
            glass[row, 10:30] = OCC_OCCUPIED
            costmap.set_static_map(OccupancyMap(0.05, (0.0, 0.0, 0.0), glass))
        elif kind < 9:
            costmap.set_params(CostmapParams(inflation_radius_m=float(rng.choice([0.4, 0.55, 0.7]))))
        before = costmap.grid()
        expected = inflate(costmap.combined_costs(), 0.05, costmap.params)
        np.testing.assert_array_equal(before.costs, expected, err_msg=f"seed {seed}, step {step}")
        if scan is not None:
            costmap.update_with_scan(*scan)  # the same scan again: the layers are as they were
            assert costmap.grid() is before


def test_a_square_clear_forgets_marks_inside_it_or_everywhere_else() -> None:
    """Nav2's region clears: the square of side reset_distance round a point, or all but it."""
    costmap = LayeredCostmap(_free_map())
    sensor = (1.5, 1.5)
    marks = np.array([[1.7, 1.5], [2.8, 1.5]])  # 0.2 m and 1.3 m from the square's centre
    costmap.update_with_scan(sensor, marks)
    frame = costmap.frame
    near, far = frame.world_to_cell(1.7, 1.5), frame.world_to_cell(2.8, 1.5)
    layer = costmap.obstacle_layer
    assert layer[near[1], near[0]] == layer[far[1], far[0]] == LETHAL_OBSTACLE

    inside = frame.cells_in_square(sensor, 1.0)
    assert len(inside) == 20 * 20  # 1 m at 0.05 m: the centres within 0.5 m each way
    costmap.clear_cells(inside)
    assert layer[near[1], near[0]] == NO_INFORMATION and layer[far[1], far[0]] == LETHAL_OBSTACLE

    costmap.update_with_scan(sensor, marks)
    outside = frame.cells_in_square(sensor, 1.0, outside=True)
    assert len(outside) + len(inside) == 60 * 60
    costmap.clear_cells(outside)
    assert layer[near[1], near[0]] == LETHAL_OBSTACLE and layer[far[1], far[0]] == NO_INFORMATION
