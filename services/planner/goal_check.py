"""Is a NavigateToPose goal one the planner can work with? Reasons, not crashes, when it is not.

A goal is refused when its frame is not the map's (``map``, or empty meaning the map), when a number
in it is not finite or its orientation quaternion has no length, when it lies outside the map, or when
its cell and every cell within the planner's snap radius are lethal, inscribed or unknown (the same
rule :class:`~services.planner.astar.AStarPlanner` uses to snap a goal, so an accepted goal is one the
search can start from).
"""

from __future__ import annotations

import math

import numpy as np

from services.planner.astar import AStarParams, step_multipliers
from services.planner.costmap import NO_INFORMATION, CostGrid
from shared.geometry import Pose2D, yaw_from_quaternion
from shared.messages import PoseStamped

#: Frames a goal may be given in: the map, or none (taken as the map).
ACCEPTED_FRAMES = ("map", "")


def goal_pose(goal: PoseStamped, accepted_frames: tuple[str, ...] = ACCEPTED_FRAMES) -> Pose2D:
    """The goal as a map pose; ``ValueError`` naming what is wrong."""
    frame = goal.header.frame_id.strip().lstrip("/")
    if frame not in accepted_frames:
        wanted = " or ".join(repr(f) for f in accepted_frames)
        raise ValueError(f"goal frame_id {goal.header.frame_id!r} is not the map frame ({wanted})")
    p, q = goal.pose.position, goal.pose.orientation
    numbers = {
        "position.x": p.x,
        "position.y": p.y,
        "position.z": p.z,
        "orientation.x": q.x,
        "orientation.y": q.y,
        "orientation.z": q.z,
        "orientation.w": q.w,
    }
    bad = [name for name, value in numbers.items() if not math.isfinite(value)]
    if bad:
        raise ValueError(f"goal pose is not finite: {', '.join(f'{n}={numbers[n]}' for n in bad)}")
    norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if norm < 1e-6:
        raise ValueError("goal orientation is a zero quaternion")
    return Pose2D.from_seq((p.x, p.y, yaw_from_quaternion(q.x / norm, q.y / norm, q.z / norm, q.w / norm)))


def check_goal_on_grid(grid: CostGrid, x_m: float, y_m: float, astar: AStarParams) -> None:
    """``ValueError`` when the goal is off the grid or in blocked space with no free cell within snapping."""
    frame = grid.frame
    ix, iy = frame.world_to_cell(x_m, y_m)
    if not frame.in_bounds(ix, iy):
        corners = frame.cells_to_world(np.array([[0, 0], [frame.width - 1, frame.height - 1]]))
        half = 0.5 * frame.resolution_m
        raise ValueError(
            f"goal ({x_m:.2f}, {y_m:.2f}) is outside the map "
            f"(x {corners[0, 0] - half:.2f}..{corners[1, 0] + half:.2f}, "
            f"y {corners[0, 1] - half:.2f}..{corners[1, 1] + half:.2f})"
        )
    reach = int(math.floor(astar.snap_radius_m / frame.resolution_m + 1e-9))
    y0, y1 = max(0, iy - reach), min(frame.height, iy + reach + 1)
    x0, x1 = max(0, ix - reach), min(frame.width, ix + reach + 1)
    window = step_multipliers(grid.costs[y0:y1, x0:x1], astar.cost_weight, astar.allow_unknown) > 0
    ys, xs = np.mgrid[y0:y1, x0:x1]
    window &= (xs - ix) ** 2 + (ys - iy) ** 2 <= reach * reach
    if window.any():
        return
    cost = int(grid.costs[iy, ix])
    what = "unknown space" if cost == NO_INFORMATION else f"lethal space (cost {cost})"
    raise ValueError(
        f"goal ({x_m:.2f}, {y_m:.2f}) is in {what} with no free cell within {astar.snap_radius_m:.2f} m"
    )
