"""End a path along its goal's heading, where there is room: arrive moving the way the goal faces.

A* plans positions only, so a path reaches its goal from whichever side was shortest, and a follower
that arrives side-on must stop, turn on the spot to the goal's heading, and (when the goal is a staging
pose, as docking's is) set off again along it. The last stretch of the path is therefore replaced, when
it helps, by the shape a car-like robot would drive: from a join point on the path (or the start) a
straight line tangent to a turning circle, the arc of that circle, and a short straight lead-in along
the goal's heading (the "line, arc" words of a Dubins path, with the heading at the join point left free
and the corner there paid for as a turn).

Each candidate (join point, turning radius, lead-in, turning left or right) must keep its centre on cells
no costlier than ``max_cost`` (or than the stretch it replaces, where that ran costlier), never on
inscribed or lethal ones, except near the robot and the goal, where it may cross what the old end crossed
there; and it must be quicker to drive than the path it replaces followed by the turn on the spot. The time is estimated as the path
follower drives: top speed, slowed in proportion on curves tighter than ``slow_radius_m``, turning no
faster than ``max_angular_radps``, and turning on the spot at a corner sharper than ``max_corner_rad``.
The quickest wins; with none, the path is left as it was. Pure numpy on a
:class:`~services.planner.costmap.CostGrid`: no Zenoh.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from services.planner.costmap import INSCRIBED_INFLATED_OBSTACLE, CostGrid
from services.planner.smoothing import orientations, resample_path
from shared.geometry import wrap_angle


@dataclass(frozen=True)
class GoalHeadingParams:
    """Where the new end may join the path, how it may turn and what it may cross."""

    #: Join points this far before the goal, along the path (the path's start too, when it is shorter).
    join_distances_m: tuple[float, ...] = (0.5, 0.8, 1.2, 1.6, 2.0, 2.5, 3.0)
    turning_radii_m: tuple[float, ...] = (0.5, 0.7, 1.0)
    #: Straight stretches along the goal's heading that end the path.
    lead_ins_m: tuple[float, ...] = (0.15, 0.4)
    #: A path that already arrives within this of the goal's heading is left alone: docking takes over
    #: from navigation before the staging pose up to 1.6 rad off the dock's heading, wherever its approach
    #: can curve in from, so a curve planned for such an arrival only lengthens the way (docs/measurements,
    #: measurement 77). Other goals turn at most that much on the spot at the goal.
    min_turn_rad: float = 1.6
    #: The curve's centre stays on cells at most this costly (128: about 0.38 m from the nearest obstacle
    #: with the default inflation), or as costly as the replaced stretch where that was costlier, never on
    #: inscribed or lethal cells; within ``end_radius_m`` of the robot and of the goal, as costly as the
    #: replaced stretch was there (the planner's own free radius round the two ends).
    max_cost: int = 128
    end_radius_m: float = 0.35
    #: The longest arc allowed (beyond it the new end would circle round).
    max_arc_rad: float = 1.25 * math.pi
    spacing_m: float = 0.05
    #: The follower's speed model (see the module docstring).
    max_linear_mps: float = 0.5
    max_angular_radps: float = 1.5
    slow_radius_m: float = 0.6
    min_curve_speed_mps: float = 0.25
    #: From the robot's own pose the new end may first turn along an arc of this radius by these angles.
    opening_radius_m: float = 0.5
    opening_sweeps_rad: tuple[float, ...] = (0.35, 0.7, 1.05)
    #: Sharper corners than this are turned on the spot (the follower's rotate-to-heading threshold).
    max_corner_rad: float = 0.785
    #: What stopping, turning on the spot and setting off again costs besides the turn itself.
    stop_and_turn_s: float = 1.0

    def __post_init__(self) -> None:
        for name in ("join_distances_m", "turning_radii_m"):
            values = getattr(self, name)
            if not values or min(values) <= 0.0:
                raise ValueError(f"{name} must be positive distances, got {values}")
        if not self.lead_ins_m or min(self.lead_ins_m) < 0.0:
            raise ValueError(f"lead_ins_m must be non-negative distances, got {self.lead_ins_m}")
        if not 0 <= self.max_cost < INSCRIBED_INFLATED_OBSTACLE:
            raise ValueError(f"max_cost must be in 0..252, got {self.max_cost}")
        for name in (
            "end_radius_m",
            "opening_radius_m",
            "max_arc_rad",
            "spacing_m",
            "max_linear_mps",
            "max_angular_radps",
            "slow_radius_m",
            "min_curve_speed_mps",
            "max_corner_rad",
        ):
            if not getattr(self, name) > 0.0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)}")


def arrive_along_heading(
    grid: CostGrid, poses: np.ndarray, params: GoalHeadingParams | None = None, start_yaw: float | None = None
) -> np.ndarray:
    """``poses`` ``(N, 3)`` (goal last, with the goal's yaw) with its end replaced by the quickest line and
    arc that arrive along the goal's heading; ``poses`` itself when none is quicker or none fits.
    ``start_yaw``: the robot's heading at the path's start (a new end joined there turns from it)."""
    p = params or GoalHeadingParams()
    poses = np.asarray(poses, dtype=float)
    if len(poses) < 3 or not np.all(np.isfinite(poses)):
        return poses
    if start_yaw is not None and not math.isfinite(start_yaw):
        start_yaw = None
    xy = poses[:, :2]
    goal, goal_yaw = xy[-1], float(poses[-1, 2])
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    total = float(arc[-1])
    arrival_turn = abs(wrap_angle(goal_yaw - _direction_before(xy, arc, total)))
    if arrival_turn < p.min_turn_rad:
        return poses
    heading = np.array([math.cos(goal_yaw), math.sin(goal_yaw)])
    best: np.ndarray | None = None
    best_join, best_s = len(xy), math.inf
    for join_m in sorted({min(d, total) for d in p.join_distances_m}):
        j = int(np.searchsorted(arc, total - join_m, side="right")) - 1
        j = min(max(j, 0), len(xy) - 2)
        replaced = xy[j:]
        old_yaw = _yaw(_direction_after(xy, arc, j))
        from_start = j == 0 and start_yaw is not None
        came_yaw = old_yaw if start_yaw is None or not from_start else start_yaw
        old_s = (
            _drive_time_s(replaced, p)
            + _corner_s(came_yaw, old_yaw, from_start, p)
            + arrival_turn / p.max_angular_radps
            + p.stop_and_turn_s
        )
        limits = _cost_limits(grid, replaced, xy[0], goal, p)
        for lead_in, lead_yaw in _openings(xy[j], came_yaw, from_start, p):
            for radius_m in p.turning_radii_m:
                for lead_m in p.lead_ins_m:
                    for side in (1.0, -1.0):
                        rest = _line_arc_lead(lead_in[-1], goal, heading, radius_m, lead_m, side, p)
                        if rest is None:
                            continue
                        tail = np.concatenate([lead_in[:-1], rest])
                        setting_off = _yaw(rest[min(3, len(rest) - 1)] - rest[0])  # over about 0.15 m
                        turn_s = _corner_s(lead_yaw, setting_off, from_start, p)
                        new_s = _drive_time_s(tail, p) + turn_s
                        if new_s < min(old_s, best_s) and _within(grid, tail, xy[0], goal, limits, p):
                            best, best_s, best_join = tail, new_s, j
    if best is None:
        return poses
    points = np.concatenate([xy[:best_join], best])
    return np.column_stack([points, orientations(points, goal_yaw)])


def _near_ends(points: np.ndarray, start: np.ndarray, goal: np.ndarray, radius_m: float) -> np.ndarray:
    """Which of ``points`` lie within ``radius_m`` of the path's start or of its goal."""
    return (np.hypot(*(points - start).T) <= radius_m) | (np.hypot(*(points - goal).T) <= radius_m)


def _cost_limits(
    grid: CostGrid, replaced: np.ndarray, start: np.ndarray, goal: np.ndarray, p: GoalHeadingParams
) -> tuple[int, int]:
    """The costs a new end may cross: ``(away from the ends, near them)``. Away from the ends, ``max_cost`` or
    what the replaced stretch crossed there, never inscribed or lethal; near the robot and the goal, also what
    the replaced stretch crossed near them (a robot standing close to a wall must still leave it)."""
    near = _near_ends(replaced, start, goal, p.end_radius_m)
    away = min(max(p.max_cost, _max_cost(grid, replaced[~near])), INSCRIBED_INFLATED_OBSTACLE - 1)
    return away, max(away, _max_cost(grid, replaced[near]))


def _within(
    grid: CostGrid,
    tail: np.ndarray,
    start: np.ndarray,
    goal: np.ndarray,
    limits: tuple[int, int],
    p: GoalHeadingParams,
) -> bool:
    near = _near_ends(tail, start, goal, p.end_radius_m)
    return _max_cost(grid, tail[~near]) <= limits[0] and _max_cost(grid, tail[near]) <= limits[1]


def _yaw(direction: np.ndarray) -> float:
    return math.atan2(float(direction[1]), float(direction[0]))


def _corner_s(from_yaw: float, to_yaw: float, standing: bool, p: GoalHeadingParams) -> float:
    """A corner on the way the follower cuts for nothing, a sharper one it turns on the spot; at the robot
    itself (``standing``: the path's start) every turn takes its time, and a sharp one a stop as well."""
    corner = abs(wrap_angle(to_yaw - from_yaw))
    if standing:
        return corner / p.max_angular_radps + (0.5 * p.stop_and_turn_s if corner > p.max_corner_rad else 0.0)
    return corner / p.max_angular_radps if corner > p.max_corner_rad else 0.0


def _openings(
    start: np.ndarray, yaw: float, from_start: bool, p: GoalHeadingParams
) -> list[tuple[np.ndarray, float]]:
    """Ways to leave ``start``: as it is, and (from the robot's own pose) along arcs that turn it first, so a
    robot already on a curve can stay on one: ``(points, heading at the last point)``."""
    openings = [(start[None, :], yaw)]
    if not from_start:
        return openings
    radius_m = p.opening_radius_m
    for side in (1.0, -1.0):
        centre = start + side * radius_m * np.array([-math.sin(yaw), math.cos(yaw)])
        for sweep in p.opening_sweeps_rad:
            steps = max(1, math.ceil(sweep * radius_m / p.spacing_m))
            turned = yaw + side * sweep * np.arange(0, steps + 1) / steps
            points = centre + side * radius_m * np.column_stack([np.sin(turned), -np.cos(turned)])
            openings.append((points, float(turned[-1])))
    return openings


def _direction_before(xy: np.ndarray, arc: np.ndarray, total: float, back_m: float = 0.2) -> float:
    """The path's direction of travel over its last ``back_m``."""
    i = int(np.searchsorted(arc, max(0.0, total - back_m), side="right")) - 1
    i = min(max(i, 0), len(xy) - 2)
    return _yaw(xy[-1] - xy[i])


def _direction_after(xy: np.ndarray, arc: np.ndarray, j: int, ahead_m: float = 0.15) -> np.ndarray:
    """The path's direction of travel from point ``j`` over the next ``ahead_m``."""
    k = int(np.searchsorted(arc, arc[j] + ahead_m, side="left"))
    k = min(max(k, j + 1), len(xy) - 1)
    return xy[k] - xy[j]


def _line_arc_lead(
    start: np.ndarray,
    goal: np.ndarray,
    heading: np.ndarray,
    radius_m: float,
    lead_m: float,
    side: float,
    p: GoalHeadingParams,
) -> np.ndarray | None:
    """Points from ``start``: straight to where it meets a circle of ``radius_m`` tangentially, round it
    (counter-clockwise for ``side`` +1) to the lead-in, then along ``heading`` to ``goal``; None when
    ``start`` is well inside the circle or the arc would circle round."""
    lead_start = goal - lead_m * heading
    normal = np.array([-heading[1], heading[0]])
    centre = lead_start + side * radius_m * normal
    offset = start - centre
    distance = float(np.hypot(*offset))
    if distance < 0.97 * radius_m:
        return None
    # The tangent point whose direction of travel round the circle leads away from ``start``; a start on
    # the circle (or a hair inside: a robot already turning onto it) joins the arc where it stands.
    on_circle = distance <= radius_m * (1.0 + 1e-6)
    spread = 0.0 if on_circle else math.acos(radius_m / distance)
    seen = math.atan2(offset[1], offset[0])
    touch = seen + side * spread
    end = math.atan2(lead_start[1] - centre[1], lead_start[0] - centre[0])
    sweep = (side * (end - touch)) % (2.0 * math.pi)
    if sweep > p.max_arc_rad:
        return None
    tangent_point = start if on_circle else centre + radius_m * np.array([math.cos(touch), math.sin(touch)])
    line = resample_path(np.array([start, tangent_point]), p.spacing_m)
    steps = max(1, math.ceil(sweep * radius_m / p.spacing_m))
    angles = touch + side * sweep * np.arange(1, steps + 1) / steps
    bend = centre + radius_m * np.column_stack([np.cos(angles), np.sin(angles)])
    lead = resample_path(np.array([lead_start, goal]), p.spacing_m)[1:]
    points = np.concatenate([line, bend, lead])
    gaps = np.hypot(*np.diff(points, axis=0).T)
    points = points[np.concatenate([[True], gaps > 0.1 * p.spacing_m])]
    if np.hypot(*(points[-1] - goal)) > 0.0:  # the goal itself ends the path, exactly
        points = np.concatenate(
            [points[:-1] if np.hypot(*(points[-1] - goal)) < 0.1 * p.spacing_m else points, goal[None, :]]
        )
    return points


def _curvatures(points: np.ndarray) -> np.ndarray:
    """Curvature at each interior point of a polyline (turn angle over the mean of its two legs)."""
    legs = np.diff(points, axis=0)
    lengths = np.hypot(legs[:, 0], legs[:, 1])
    headings = np.arctan2(legs[:, 1], legs[:, 0])
    turn = np.abs((np.diff(headings) + math.pi) % (2.0 * math.pi) - math.pi)
    return turn / np.maximum(0.5 * (lengths[1:] + lengths[:-1]), 1e-9)


def _max_cost(grid: CostGrid, points: np.ndarray) -> int:
    """The highest cost under ``points`` (0 for none); unknown and off-grid read as ``NO_INFORMATION``,
    above lethal, so no limit below it lets them pass."""
    return int(grid.costs_at(points).max()) if len(points) else 0


def _drive_time_s(points: np.ndarray, p: GoalHeadingParams) -> float:
    """Seconds to drive a polyline as the follower would (see the module docstring)."""
    if len(points) < 2:
        return 0.0
    legs = np.hypot(*np.diff(points, axis=0).T)
    kappa = np.concatenate([[0.0], _curvatures(points)])
    radius = 1.0 / np.maximum(kappa, 1e-9)
    regulated = np.maximum(p.max_linear_mps * radius / p.slow_radius_m, p.min_curve_speed_mps)
    speed = np.minimum(p.max_linear_mps, regulated)
    speed = np.minimum(speed, p.max_angular_radps * radius)
    return float(np.sum(legs / np.maximum(speed, 1e-3)))
