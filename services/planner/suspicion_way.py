"""A way through suspected glass, for when suspicion alone closes every way to a goal.

Suspicion (:meth:`GlassMemory.suspicion_mask <services.planner.glass_memory.GlassMemory.suspicion_mask>`)
is a guess: floor the sonar never looked at, near glass it heard, may hold more of the pane. Within
0.3 m of both sides of a glass doorway, or of a pane's end and a box, the guesses can close the only way
to the goal, and the robot, which looks only where it drives, never faces the floor that would clear
them. Recovery after recovery the planner found no path; forgetting the glass and looking round heard
the panes again and closed the way again (measurement 104 has the generated rooms where it did).

So when no path is found, the planner asks this module for a way on the costmap with suspicion cut to
the inner half of its radius (marks, held arcs and a pane's extension count in full). The suspected cells
the robot would sweep along it, with its circumscribed radius and a cell to spare, are excused from the
outer half: the plan goes through them, keeping the inner half's margin from every heard pane end, and
the sonar looks at them as the robot drives there. What it hears there is held as glass at once and
marked as the evidence grows, as anywhere else; suspicion elsewhere stays whole.

Pure numpy and the planner's own search: no bus, no thread.
"""

from __future__ import annotations

import numpy as np

from services.planner.astar import PlanningError
from services.planner.costmap import CostGrid
from services.planner.distance_transform import squared_distance_to_marks
from services.planner.global_planner import GlobalPlanner
from shared.geometry import Pose2D


def reachable(planner: GlobalPlanner, grid: CostGrid, start: Pose2D, goal: Pose2D) -> bool:
    """Whether ``planner`` finds a path from ``start`` to ``goal`` on ``grid``."""
    try:
        planner.compute_path(grid, start, goal)
    except PlanningError:
        return False
    return True


def swept_cells(grid: CostGrid, points_xy: np.ndarray, reach_m: float) -> np.ndarray:
    """Boolean ``(height, width)``: the cells within ``reach_m`` of any of ``points_xy`` ``(N, 2)``."""
    frame = grid.frame
    on_path = np.zeros(frame.shape, dtype=bool)
    cells = frame.world_to_cells(np.asarray(points_xy, dtype=float).reshape(-1, 2))
    cells = cells[frame.cells_in_bounds(cells)]
    on_path[cells[:, 1], cells[:, 0]] = True
    reach_cells = reach_m / frame.resolution_m
    return squared_distance_to_marks(on_path, reach_cells) <= reach_cells * reach_cells


def way_through_suspicion(
    planner: GlobalPlanner,
    without_suspicion: CostGrid,
    suspicion: np.ndarray,
    start: Pose2D,
    goal: Pose2D,
    reach_m: float,
) -> np.ndarray | None:
    """The suspected cells (of ``suspicion``) within ``reach_m`` of a path from ``start`` to ``goal`` on
    ``without_suspicion`` (the costmap with less of it); None when there is no such path either, and the
    way is closed by more than the guess."""
    try:
        path = planner.compute_path(without_suspicion, start, goal)
    except PlanningError:
        return None
    points = np.concatenate([path.poses[:, :2], np.asarray(path.grid_points, dtype=float).reshape(-1, 2)])
    return suspicion & swept_cells(without_suspicion, points, reach_m)
