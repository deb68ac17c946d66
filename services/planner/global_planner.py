"""ComputePathToPose: A* on the costmap, then shortcutting and smoothing into poses ~0.05 m apart.

Large grids are searched at half resolution (nav2 Smac planner's ``downsample_costmap``): the coarse
grid is conservative (a coarse cell is as costly as the worst cell under it), and smoothing then runs
against the full-resolution costmap. Small rooms are searched at full resolution.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from services.planner.astar import AStarParams, AStarPlanner
from services.planner.costmap import CostGrid
from services.planner.smoothing import SmoothingParams, path_length_m, smooth_path
from shared.geometry import Pose2D

PoseLike = Pose2D | tuple[float, float, float]


@dataclass(frozen=True)
class GlobalPlannerParams:
    """Search and smoothing settings. Keep ``cost_weight`` and ``allow_unknown`` the same in both, so
    the smoother judges shortcuts by the cost the search minimised."""

    astar: AStarParams = field(default_factory=AStarParams)
    smoothing: SmoothingParams = field(default_factory=SmoothingParams)
    #: Grids with more cells than this are searched at ``downsample_factor`` times coarser resolution.
    max_full_resolution_cells: int = 90_000
    downsample_factor: int = 2

    def __post_init__(self) -> None:
        if self.downsample_factor < 1:
            raise ValueError(f"downsample_factor must be a positive integer, got {self.downsample_factor}")


@dataclass(frozen=True, eq=False)
class PlannedPath:
    """A path in the map frame, ready for a follower."""

    #: ``(N, 3)`` poses ``(x, y, yaw)``, first at the start position, last at the goal with the goal's yaw.
    poses: np.ndarray
    length_m: float
    #: The A* path before smoothing (cell centres, ends at the exact start/goal when not snapped).
    grid_points: np.ndarray
    start_snapped: bool
    goal_snapped: bool
    #: Resolution the search ran at (the costmap's, or coarser for large grids).
    search_resolution_m: float
    expansions: int
    planning_time_s: float


class GlobalPlanner:
    """Plans with :class:`AStarPlanner` and :func:`smooth_path`; reuses search arrays across calls."""

    def __init__(self, params: GlobalPlannerParams | None = None) -> None:
        self.params = params or GlobalPlannerParams()
        self._astar = AStarPlanner(self.params.astar)
        self._coarse_of: CostGrid | None = None
        self._coarse: CostGrid | None = None

    def compute_path(self, grid: CostGrid, start: PoseLike, goal: PoseLike) -> PlannedPath:
        """Plan from ``start`` to ``goal`` (map frame).

        Raises :class:`~services.planner.astar.PlanningError` when an end is unusable or unreachable.
        """
        t0 = time.perf_counter()
        start_pose, goal_pose = _pose(start), _pose(goal)
        search_grid = self._search_grid(grid)
        found = self._astar.plan(search_grid, (start_pose.x, start_pose.y), (goal_pose.x, goal_pose.y))
        points = found.points_xy
        if len(points) == 1:
            points = np.array([[start_pose.x, start_pose.y], [goal_pose.x, goal_pose.y]])
        poses = smooth_path(grid, points, goal_pose.yaw, self.params.smoothing)
        return PlannedPath(
            poses=poses,
            length_m=path_length_m(poses),
            grid_points=found.points_xy,
            start_snapped=found.start_snapped,
            goal_snapped=found.goal_snapped,
            search_resolution_m=search_grid.frame.resolution_m,
            expansions=found.expansions,
            planning_time_s=time.perf_counter() - t0,
        )

    def _search_grid(self, grid: CostGrid) -> CostGrid:
        if grid.costs.size <= self.params.max_full_resolution_cells or self.params.downsample_factor == 1:
            return grid
        if self._coarse_of is not grid:
            self._coarse = grid.downsampled(self.params.downsample_factor)
            self._coarse_of = grid
        assert self._coarse is not None
        return self._coarse


def _pose(pose: PoseLike) -> Pose2D:
    if isinstance(pose, Pose2D):
        return pose
    x, y, yaw = (float(v) for v in pose)
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        raise ValueError(f"pose must be three finite numbers, got {pose}")
    return Pose2D(x, y, yaw)
