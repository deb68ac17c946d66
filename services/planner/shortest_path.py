"""The yardstick for navigation runs: the shortest collision-free path through a world, glass included.

Every obstacle the robot can touch is drawn (glass too, unlike the lidar map), inflated only to the
inscribed radius (the robot's centre must stay that far from everything), searched with A* at zero
cost weight (pure length), and the grid path straightened by line-of-sight shortcuts. A real
rectangular robot needs more room than its inscribed circle, so this length is a lower bound on any
path it can drive; divided by the speed limit it bounds the time to goal from below.
"""

from __future__ import annotations

import msgspec
import numpy as np

from services.planner.astar import AStarParams, AStarPlanner
from services.planner.costmap import CostGrid, CostmapParams, LayeredCostmap
from services.planner.occupancy_map import OccupancyMap
from services.planner.rasterize import map_from_world
from services.planner.smoothing import SmoothingParams, path_length_m, shortcut_path
from shared.world import ROBOT_LENGTH_M, ROBOT_WIDTH_M, World


def solid_map(world: World, resolution_m: float = 0.05) -> OccupancyMap:
    """Every surface the robot can touch, glass too, rasterised."""
    solid = msgspec.structs.replace(world, walls=[*world.walls, *world.glass], glass=[])
    return map_from_world(solid, resolution_m=resolution_m)


def solid_grid(
    world: World,
    resolution_m: float = 0.05,
    robot_length_m: float = ROBOT_LENGTH_M,
    robot_width_m: float = ROBOT_WIDTH_M,
    occupancy: OccupancyMap | None = None,
) -> CostGrid:
    """Every surface the robot can touch (glass too, or ``occupancy`` already drawn by :func:`solid_map`),
    inflated to the inscribed radius only."""
    if occupancy is None:
        occupancy = solid_map(world, resolution_m)
    inscribed_radius_m = 0.5 * min(robot_length_m, robot_width_m)
    params = CostmapParams(
        robot_length_m=robot_length_m, robot_width_m=robot_width_m, inflation_radius_m=inscribed_radius_m
    )
    return LayeredCostmap(occupancy, params).grid()


#: How far an end may lie inside the inscribed zone of the grid's rasterised surfaces. A docking pose
#: puts the robot's centre as close to the dock as its own front allows, and the dock's rasterised cells
#: reach up to a cell's diagonal past its true outline (more at angles that are no multiple of 90
#: degrees): the ends are joined to the nearest free cell this close, by a straight last leg.
END_SNAP_RADIUS_M = 0.1


def shortest_path(grid: CostGrid, start_xy: tuple[float, float], goal_xy: tuple[float, float]) -> np.ndarray:
    """The shortest path's corner points ``(N, 2)`` on a :func:`solid_grid`; ``PlanningError`` if none.

    An end inside the inscribed zone (a docking pose, see :data:`END_SNAP_RADIUS_M`) is reached from the
    nearest free cell by a straight leg; the path's other points all lie in free space.
    """
    found = AStarPlanner(AStarParams(cost_weight=0.0, snap_radius_m=END_SNAP_RADIUS_M)).plan(
        grid, start_xy, goal_xy
    )
    points = shortcut_path(grid, found.points_xy, SmoothingParams(max_cost=252, cost_weight=0.0))
    if found.goal_snapped:
        points = np.concatenate([points, np.asarray(goal_xy, dtype=float)[None, :]])
    return points


def shortest_path_length_m(
    world: World,
    start_xy: tuple[float, float],
    goal_xy: tuple[float, float],
    resolution_m: float = 0.05,
    robot_length_m: float = ROBOT_LENGTH_M,
    robot_width_m: float = ROBOT_WIDTH_M,
) -> float:
    """Length of the shortest path for the robot's inscribed circle; ``PlanningError`` if there is none."""
    grid = solid_grid(world, resolution_m, robot_length_m, robot_width_m)
    return path_length_m(shortest_path(grid, start_xy, goal_xy))
