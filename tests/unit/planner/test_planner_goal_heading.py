"""A path's end along its goal's heading: it arrives facing the goal's way, only where there is room,
and never over costlier cells than the path it replaces."""

from __future__ import annotations

import math

import numpy as np
import pytest

from services.planner.costmap import LayeredCostmap
from services.planner.global_planner import GlobalPlanner, GlobalPlannerParams
from services.planner.goal_heading import GoalHeadingParams, arrive_along_heading
from services.planner.occupancy_map import OCC_FREE, OCC_OCCUPIED, OccupancyMap
from shared.geometry import wrap_angle

RESOLUTION_M = 0.05
#: Side-on arrivals (90 degrees off) count: the default leaves up to 1.6 rad to docking's takeover.
SIDE_ON = GoalHeadingParams(min_turn_rad=1.0)


def _room(size_m: float = 6.0, blocks: tuple[tuple[float, float, float, float], ...] = ()) -> LayeredCostmap:
    """A walled square room from (0, 0), with rectangular blocks ``(x0, y0, x1, y1)`` inside."""
    cells = round(size_m / RESOLUTION_M)
    data = np.full((cells, cells), OCC_FREE, dtype=np.int8)
    data[[0, -1], :] = OCC_OCCUPIED
    data[:, [0, -1]] = OCC_OCCUPIED
    for x0, y0, x1, y1 in blocks:
        data[
            round(y0 / RESOLUTION_M) : round(y1 / RESOLUTION_M),
            round(x0 / RESOLUTION_M) : round(x1 / RESOLUTION_M),
        ] = OCC_OCCUPIED
    return LayeredCostmap(OccupancyMap(RESOLUTION_M, (0.0, 0.0, 0.0), data))


def _straight(start: tuple[float, float], goal: tuple[float, float], goal_yaw: float) -> np.ndarray:
    count = math.ceil(math.dist(start, goal) / RESOLUTION_M)
    xy = np.linspace(start, goal, count + 1)
    yaw = np.full(len(xy), math.atan2(goal[1] - start[1], goal[0] - start[0]))
    yaw[-1] = goal_yaw
    return np.column_stack([xy, yaw])


def _arrival_yaw(poses: np.ndarray, back_m: float = 0.15) -> float:
    xy = poses[:, :2]
    before = xy[np.hypot(*(xy - xy[-1]).T) >= back_m][-1]
    return math.atan2(xy[-1, 1] - before[1], xy[-1, 0] - before[0])


def test_a_side_on_arrival_becomes_one_along_the_goal_heading() -> None:
    grid = _room().grid()
    side_on = _straight((5.0, 3.0), (2.0, 3.0), -math.pi / 2)  # driving west to a goal that faces south
    poses = arrive_along_heading(grid, side_on, SIDE_ON, start_yaw=math.pi)
    assert poses is not side_on
    assert np.allclose(poses[-1, :2], side_on[-1, :2])
    assert poses[-1, 2] == pytest.approx(-math.pi / 2)
    assert abs(wrap_angle(_arrival_yaw(poses) + math.pi / 2)) < 0.1
    steps = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    assert steps.max() <= 0.051 and steps.min() > 0.0
    assert grid.costs_at(poses[:, :2]).max() <= GoalHeadingParams().max_cost


def test_a_path_already_arriving_along_the_heading_is_left_alone() -> None:
    grid = _room().grid()
    aligned = _straight((2.0, 5.0), (2.0, 2.0), -math.pi / 2)
    assert arrive_along_heading(grid, aligned, start_yaw=-math.pi / 2) is aligned


def test_no_room_to_turn_leaves_the_path_as_it_was() -> None:
    # A corridor 0.9 m wide ending at the goal: no curve into a heading across it fits.
    grid = _room(blocks=((0.0, 0.0, 6.0, 2.55), (0.0, 3.45, 6.0, 6.0))).grid()
    side_on = _straight((5.0, 3.0), (2.0, 3.0), -math.pi / 2)
    assert arrive_along_heading(grid, side_on, SIDE_ON, start_yaw=math.pi) is side_on


def test_an_arrival_within_the_turn_allowed_is_left_alone() -> None:
    grid = _room().grid()
    nearly = _straight((5.0, 3.0), (2.0, 3.0), math.pi - 0.3)
    assert (
        arrive_along_heading(grid, nearly, GoalHeadingParams(min_turn_rad=0.35), start_yaw=math.pi) is nearly
    )


def test_the_new_end_crosses_no_costlier_cells_than_the_old_one_away_from_its_ends() -> None:
    """Starts and goals drawn anywhere the robot fits, next to walls too: away from the robot and the goal the
    new end keeps to ``max_cost`` or to what the old end crossed there, never inscribed or lethal; near them,
    to what the old end crossed near them. Every step is a real one."""
    rng = np.random.default_rng(7)
    p = SIDE_ON
    planner = GlobalPlanner(GlobalPlannerParams(goal_heading=None))
    changed = 0
    for trial in range(240):
        if trial % 8 == 0:
            blocks = tuple(
                (x, y, x + w, y + h)
                for x, y, w, h in rng.uniform((0.5, 0.5, 0.2, 0.2), (5.0, 5.0, 1.0, 1.0), (6, 4))
            )
            grid = _room(blocks=blocks).grid()
            fits = np.argwhere(grid.costs < 253)
        start_cell, goal_cell = fits[rng.integers(len(fits))], fits[rng.integers(len(fits))]
        start = grid.frame.cell_to_world(int(start_cell[1]), int(start_cell[0]))
        goal = grid.frame.cell_to_world(int(goal_cell[1]), int(goal_cell[0]))
        try:
            plain = planner.compute_path(grid, (*start, 0.0), (*goal, float(rng.uniform(-math.pi, math.pi))))
        except Exception:
            continue
        poses = arrive_along_heading(grid, plain.poses, p, start_yaw=float(rng.uniform(-math.pi, math.pi)))
        assert np.array_equal(poses[-1], plain.poses[-1]) and np.array_equal(poses[0, :2], plain.poses[0, :2])
        if poses is plain.poses:
            continue
        changed += 1
        assert np.hypot(*np.diff(poses[:, :2], axis=0).T).min() >= 0.1 * p.spacing_m
        ends = plain.poses[0, :2], plain.poses[-1, :2]

        def near(xy: np.ndarray, ends: tuple[np.ndarray, np.ndarray] = ends) -> np.ndarray:
            return (np.hypot(*(xy - ends[0]).T) <= p.end_radius_m) | (
                np.hypot(*(xy - ends[1]).T) <= p.end_radius_m
            )

        old, new = plain.poses[:, :2], poses[:, :2]
        old_away = grid.costs_at(old[~near(old)]).max(initial=0)
        new_away = grid.costs_at(new[~near(new)]).max(initial=0)
        assert new_away <= max(p.max_cost, min(int(old_away), 252)) and new_away < 253
        assert grid.costs_at(new[near(new)]).max(initial=0) <= max(p.max_cost, grid.costs_at(old).max())
    assert changed >= 15, f"only {changed} of 240 paths had their end replaced: the test would prove little"


def test_the_planner_ends_paths_along_the_goal_heading_unless_told_not_to() -> None:
    grid = _room().grid()
    start, goal = (5.0, 3.2, math.pi), (2.0, 3.0, -math.pi / 2)
    plain = GlobalPlanner(GlobalPlannerParams(goal_heading=None)).compute_path(grid, start, goal)
    curved = GlobalPlanner(GlobalPlannerParams(goal_heading=SIDE_ON)).compute_path(grid, start, goal)
    assert abs(wrap_angle(_arrival_yaw(plain.poses) + math.pi / 2)) > 1.0
    assert abs(wrap_angle(_arrival_yaw(curved.poses) + math.pi / 2)) < 0.1
    assert curved.length_m == pytest.approx(float(np.hypot(*np.diff(curved.poses[:, :2], axis=0).T).sum()))


def test_by_default_only_arrivals_beyond_docking_s_takeover_are_curved() -> None:
    grid = _room().grid()
    side_on = _straight((5.0, 3.0), (2.0, 3.0), -math.pi / 2)  # 1.57 rad off: docking takes over from there
    assert arrive_along_heading(grid, side_on, start_yaw=math.pi) is side_on
    beyond = _straight((5.0, 3.0), (2.0, 3.0), -1.2)  # 1.94 rad off: docking would stop there to turn
    poses = arrive_along_heading(grid, beyond, start_yaw=math.pi)
    assert poses is not beyond and abs(wrap_angle(_arrival_yaw(poses) + 1.2)) < 0.1
    doubling_back = _straight(
        (5.0, 3.0), (2.0, 3.0), -0.3
    )  # 2.8 rad off: turning there is quicker than a loop
    assert arrive_along_heading(grid, doubling_back, start_yaw=math.pi) is doubling_back


def test_non_finite_input_is_not_an_error() -> None:
    grid = _room().grid()
    side_on = _straight((5.0, 3.0), (2.0, 3.0), -math.pi / 2)
    assert np.array_equal(arrive_along_heading(grid, side_on, SIDE_ON, start_yaw=math.nan)[-1], side_on[-1])
    broken = side_on.copy()
    broken[-1, 2] = math.nan
    assert arrive_along_heading(grid, broken, SIDE_ON, start_yaw=math.pi) is broken


def test_bad_parameters_are_refused_with_their_name() -> None:
    with pytest.raises(ValueError, match="turning_radii_m"):
        GoalHeadingParams(turning_radii_m=(0.0,))
    with pytest.raises(ValueError, match="max_cost"):
        GoalHeadingParams(max_cost=253)
