"""ComputePathToPose: A* on the costmap, then shortcutting and smoothing into poses ~0.05 m apart.

Room to turn: the search keeps the robot's inscribed circle off obstacles, but the footprint is a
rectangle, and a gap that only the circle fits through leaves the follower's footprint check refusing
every move inside it. So when the path passes cells closer to an obstacle than the circumscribed
radius (``preferred_clearance_cost`` and above), the planner also searches with those cells closed
(except around the start and the goal) and takes that path unless it is much longer.

Large grids are searched at half resolution (nav2 Smac planner's ``downsample_costmap``): the coarse
grid is conservative (a coarse cell is as costly as the worst cell under it), and smoothing then runs
against the full-resolution costmap. Small rooms are searched at full resolution.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from services.planner.astar import AStarParams, AStarPlanner, PlanningError
from services.planner.costmap import INSCRIBED_INFLATED_OBSTACLE, CostGrid
from services.planner.goal_heading import GoalHeadingParams, arrive_along_heading
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
    #: Cells at or above this cost (closer to an obstacle than the circumscribed radius) are avoided when
    #: a path without them is at most ``clearance_detour_factor`` times longer (0: off).
    preferred_clearance_cost: int = 0
    clearance_detour_factor: float = 2.0
    #: Around the start and the goal the costs stay as they are, so a robot can leave a tight spot.
    clearance_free_radius_m: float = 0.35
    #: End the path along the goal's heading where there is room (:mod:`services.planner.goal_heading`);
    #: None: the path ends however A* reached the goal, and the follower turns there on the spot.
    goal_heading: GoalHeadingParams | None = field(default_factory=GoalHeadingParams)

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
        start_pose = _pose(start)
        path = self._roomy_path(grid, start_pose, _pose(goal), t0)
        if self.params.goal_heading is None or path.goal_snapped:
            return path
        poses = arrive_along_heading(grid, path.poses, self.params.goal_heading, start_pose.yaw)
        if poses is path.poses:
            return path
        return replace(
            path, poses=poses, length_m=path_length_m(poses), planning_time_s=time.perf_counter() - t0
        )

    def _roomy_path(self, grid: CostGrid, start_pose: Pose2D, goal_pose: Pose2D, t0: float) -> PlannedPath:
        """The A* path, or one with room to turn when that is not much longer (see the module docstring)."""
        path = self._plan_on(grid, start_pose, goal_pose, t0)
        threshold = self.params.preferred_clearance_cost
        if threshold <= 0 or not np.any(grid.costs_at(path.grid_points) >= threshold):
            return path  # the usual case: nowhere too tight to turn, no second grid to build
        roomy = self._with_clearance(grid, start_pose, goal_pose)
        if roomy is not None and _passes_closed_cells(roomy, grid, path.grid_points):
            try:
                alternative = self._plan_on(roomy, start_pose, goal_pose, t0)
            except PlanningError:
                return path
            if alternative.length_m <= self.params.clearance_detour_factor * path.length_m:
                return replace(alternative, expansions=alternative.expansions + path.expansions)
        return path

    def _plan_on(self, grid: CostGrid, start_pose: Pose2D, goal_pose: Pose2D, t0: float) -> PlannedPath:
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

    def _with_clearance(self, grid: CostGrid, start: Pose2D, goal: Pose2D) -> CostGrid | None:
        """The grid with the cells too tight to turn in closed, but around the two ends; None if none are."""
        threshold = self.params.preferred_clearance_cost
        costs = grid.costs
        tight = (costs >= threshold) & (costs < INSCRIBED_INFLATED_OBSTACLE)
        frame = grid.frame
        reach = int(math.ceil(self.params.clearance_free_radius_m / frame.resolution_m))
        for end in (start, goal):
            ix, iy = frame.world_to_cell(end.x, end.y)
            x0, x1 = max(ix - reach, 0), min(ix + reach + 1, costs.shape[1])
            y0, y1 = max(iy - reach, 0), min(iy + reach + 1, costs.shape[0])
            if x0 < x1 and y0 < y1:
                yy, xx = np.mgrid[y0:y1, x0:x1]
                near = (xx - ix) ** 2 + (yy - iy) ** 2 <= reach * reach
                tight[y0:y1, x0:x1] &= ~near
        if not tight.any():
            return None
        return CostGrid(
            frame, np.where(tight, np.uint8(INSCRIBED_INFLATED_OBSTACLE), costs).astype(costs.dtype)
        )

    def _search_grid(self, grid: CostGrid) -> CostGrid:
        if grid.costs.size <= self.params.max_full_resolution_cells or self.params.downsample_factor == 1:
            return grid
        if self._coarse_of is not grid:
            self._coarse = grid.downsampled(self.params.downsample_factor)
            self._coarse_of = grid
        assert self._coarse is not None
        return self._coarse


def _passes_closed_cells(roomy: CostGrid, grid: CostGrid, points_xy: np.ndarray) -> bool:
    """Whether a path's points cross cells that ``roomy`` closes and ``grid`` leaves open."""
    if len(points_xy) == 0:
        return False
    closed = (roomy.costs >= INSCRIBED_INFLATED_OBSTACLE) & (grid.costs < INSCRIBED_INFLATED_OBSTACLE)
    cells = grid.frame.world_to_cells(np.asarray(points_xy, dtype=float))
    ok = grid.frame.cells_in_bounds(cells)
    cells = cells[ok]
    return bool(np.any(closed[cells[:, 1], cells[:, 0]]))


def _pose(pose: PoseLike) -> Pose2D:
    if isinstance(pose, Pose2D):
        return pose
    x, y, yaw = (float(v) for v in pose)
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        raise ValueError(f"pose must be three finite numbers, got {pose}")
    return Pose2D(x, y, yaw)
