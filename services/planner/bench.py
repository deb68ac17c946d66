"""Planning speed on a 20 m x 20 m room at 0.05 m (400 x 400 cells): the numbers ``zendock bench planner``
reports.

The room has an inner wall with a doorway, a partition, a row of boxes and a dock, so paths must bend
around obstacles and through inflated space. Each repeat plans between a fixed set of start/goal pairs
that cross the room; times are medians over all plans.
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from typing import Any

from services.planner.astar import AStarParams, AStarPlanner
from services.planner.costmap import CostmapParams, LayeredCostmap
from services.planner.global_planner import GlobalPlanner, GlobalPlannerParams
from services.planner.rasterize import map_from_world
from shared.structs import validate
from shared.world import World

#: Start/goal pairs (map frame) that cross the room and need the doorway or go around boxes.
BENCH_ROUTES: tuple[tuple[tuple[float, float], tuple[float, float]], ...] = (
    ((-9.0, -9.0), (9.0, 9.0)),
    ((-9.0, 9.0), (9.0, -9.0)),
    ((-8.5, 0.0), (8.5, 0.5)),
    ((0.0, -9.0), (1.0, 9.0)),
    ((5.0, 8.0), (-6.0, -8.0)),
    ((-2.0, 3.0), (2.0, -3.0)),
)


def bench_world() -> World:
    """A 20 m x 20 m room with a wall and doorway, a partition, boxes and a dock."""
    boxes = [
        {"pose": [x, -3.5, 0.3 * i], "size": [0.8, 0.6]} for i, x in enumerate((-7.0, -4.0, -1.0, 2.0, 5.0))
    ]
    boxes += [
        {"pose": [-5.0, 6.0, 0.0], "size": [1.5, 1.5]},
        {"pose": [6.5, 4.0, math.pi / 6], "size": [1.0, 2.0]},
    ]
    return validate(
        World,
        {
            "name": "bench_room",
            "bounds": [-10.0, -10.0, 10.0, 10.0],
            "walls": [
                [[-10.0, 2.0], [3.0, 2.0]],
                [[4.5, 2.0], [10.0, 2.0]],
                [[0.0, -10.0], [0.0, -6.0]],
                [[-6.0, -6.5], [-2.0, 0.5]],
            ],
            "boxes": boxes,
            "docks": [{"id": "home", "pose": [8.0, -9.2, -math.pi / 2]}],
            "robot": {"start": [-9.0, -9.0, 0.0]},
        },
        "bench_room",
    )


def _median_ms(fn: Callable[[], Any], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1000.0 * statistics.median(times)


def bench_planning(repeats: int = 5, resolution_m: float = 0.05) -> dict[str, float]:
    """Median milliseconds of each planning stage on the bench room, with grid size and path stats.

    Every plan starts cold (fresh planner, as after a costmap update). ``plan_ms`` is the default
    :class:`GlobalPlanner` (search at half resolution on this grid, smoothing at full resolution);
    ``plan_full_resolution_ms`` searches at full resolution; ``astar_ms`` is the bare full-resolution search.
    """
    world = bench_world()
    occupancy = map_from_world(world, resolution_m=resolution_m, padding_m=0.0)
    costmap = LayeredCostmap(occupancy, CostmapParams())

    def rebuild() -> None:
        costmap.clear()
        costmap.grid()

    inflate_ms = _median_ms(rebuild, repeats)
    grid = costmap.grid()
    full_resolution = GlobalPlannerParams(max_full_resolution_cells=grid.costs.size)

    stages: dict[str, list[float]] = {"astar": [], "plan": [], "plan_full_resolution": []}
    expansions, lengths = [], []
    for _ in range(repeats):
        for start, goal in BENCH_ROUTES:
            t0 = time.perf_counter()
            found = AStarPlanner(AStarParams()).plan(grid, start, goal)
            stages["astar"].append(time.perf_counter() - t0)
            expansions.append(found.expansions)
            t0 = time.perf_counter()
            path = GlobalPlanner().compute_path(grid, (*start, 0.0), (*goal, 0.0))
            stages["plan"].append(time.perf_counter() - t0)
            lengths.append(path.length_m)
            t0 = time.perf_counter()
            GlobalPlanner(full_resolution).compute_path(grid, (*start, 0.0), (*goal, 0.0))
            stages["plan_full_resolution"].append(time.perf_counter() - t0)
    result = {
        "grid_width": float(grid.frame.width),
        "grid_height": float(grid.frame.height),
        "routes": float(len(BENCH_ROUTES)),
        "inflation_ms": inflate_ms,
        "astar_expansions": float(statistics.median(expansions)),
        "path_length_m": float(statistics.median(lengths)),
    }
    for name, times in stages.items():
        result[f"{name}_ms"] = 1000.0 * statistics.median(times)
        result[f"{name}_max_ms"] = 1000.0 * max(times)
    return result


def main(argv: list[str] | None = None) -> int:
    """``python -m services.planner.bench [--repeats N] [--resolution R]``: medians as one JSON line."""
    import argparse  # noqa: PLC0415
    import json  # noqa: PLC0415

    parser = argparse.ArgumentParser(
        prog="python -m services.planner.bench", description="planning time benchmark"
    )
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--resolution", type=float, default=0.05)
    args = parser.parse_args(argv)
    print(json.dumps({k: round(v, 2) for k, v in bench_planning(args.repeats, args.resolution).items()}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
