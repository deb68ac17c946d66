"""Suspected glass that alone closes every way to a goal is excused along one way (its outer half: the inner
half of the radius round heard glass stays), and nowhere else; a way closed by walls stays closed, and a way
already open excuses nothing."""

from __future__ import annotations

import logging

import numpy as np

from services.planner.costmap import LETHAL_OBSTACLE, NO_INFORMATION
from services.planner.costmap_updater import CostmapUpdater
from services.planner.global_planner import GlobalPlanner
from services.planner.occupancy_map import OCC_FREE, OCC_OCCUPIED, OccupancyMap
from services.planner.params import Params
from services.planner.suspicion_way import reachable
from shared.geometry import Pose2D
from shared.pose_tracking import PoseTrack

RESOLUTION_M = 0.05
START = Pose2D(1.0, 2.0, 0.0)
GOAL = Pose2D(5.0, 2.0, 0.0)
#: The wall across the room at x = 3 m (column 60) and its doorway, rows 32-47 (y 1.6-2.4 m).
WALL_COLUMN = 60
DOOR_ROWS = slice(32, 48)
#: Glass heard once, far from the way (x 1.0, y 3.5): its suspicion is none of the way's business.
FAR_MARK = (70, 20)


def _updater(door: bool = True) -> CostmapUpdater:
    """A 6 x 4 m room cut in two by a wall with a 0.8 m doorway, and glass marked at both jambs (the wall's
    cells beside the doorway) and once far away, nothing else looked at: suspicion round the jambs leaves
    0.2 m of the doorway, too little for the robot."""
    data = np.full((80, 120), OCC_FREE, dtype=np.int8)
    data[:, WALL_COLUMN] = OCC_OCCUPIED
    if door:
        data[DOOR_ROWS, WALL_COLUMN] = OCC_FREE
    layers = CostmapUpdater(Params(), PoseTrack(), logging.getLogger("test"))
    layers.set_map(OccupancyMap(RESOLUTION_M, (0.0, 0.0, 0.0), data))
    assert layers.glass is not None
    layer = np.full(data.shape, NO_INFORMATION, dtype=np.uint8)
    layer[DOOR_ROWS.start - 1, WALL_COLUMN] = LETHAL_OBSTACLE
    layer[DOOR_ROWS.stop, WALL_COLUMN] = LETHAL_OBSTACLE
    layer[FAR_MARK] = LETHAL_OBSTACLE
    layers.glass.restore(layer)
    layers.apply_glass()
    return layers


def _planner() -> GlobalPlanner:
    return GlobalPlanner(Params().planner_params())


def test_suspicion_that_alone_closes_the_doorway_is_excused_along_one_way_only() -> None:
    layers = _updater()
    assert layers.glass is not None
    suspected_before = layers.glass.suspicion_mask()
    assert not reachable(_planner(), layers.grid(), START, GOAL), "the set-up: suspicion closes the doorway"

    excused = layers.open_way_through_suspicion(START, GOAL, _planner())

    assert excused > 0
    assert reachable(_planner(), layers.grid(), START, GOAL), "the doorway is open once excused"
    suspected_after = layers.glass.suspicion_mask()
    assert np.count_nonzero(suspected_before & ~suspected_after) == excused
    far_rows, far_columns = slice(FAR_MARK[0] - 6, FAR_MARK[0] + 7), slice(FAR_MARK[1] - 6, FAR_MARK[1] + 7)
    assert np.array_equal(suspected_after[far_rows, far_columns], suspected_before[far_rows, far_columns]), (
        "suspicion far from the way stays"
    )
    jamb_row = DOOR_ROWS.start - 1
    assert suspected_after[jamb_row + 1, WALL_COLUMN], "the inner half of the radius round heard glass stays"
    assert suspected_before[jamb_row + 5, WALL_COLUMN] and not suspected_after[jamb_row + 5, WALL_COLUMN], (
        "the outer half, on the way, is excused"
    )


def test_a_way_that_is_already_open_excuses_nothing() -> None:
    layers = _updater()
    assert layers.glass is not None
    layers.open_way_through_suspicion(START, GOAL, _planner())
    suspected = layers.glass.suspicion_mask()
    assert layers.open_way_through_suspicion(START, GOAL, _planner()) == 0
    assert np.array_equal(layers.glass.suspicion_mask(), suspected)


def test_a_way_closed_by_a_wall_stays_closed() -> None:
    layers = _updater(door=False)
    assert layers.glass is not None
    suspected = layers.glass.suspicion_mask()
    assert layers.open_way_through_suspicion(START, GOAL, _planner()) == 0
    assert np.array_equal(layers.glass.suspicion_mask(), suspected)
    assert not reachable(_planner(), layers.grid(), START, GOAL)


def test_forgetting_the_doorway_forgets_that_its_suspicion_was_excused() -> None:
    """A recovery that clears round the robot starts that floor afresh: its suspicion excused no more."""
    layers = _updater()
    assert layers.glass is not None
    layers.open_way_through_suspicion(START, GOAL, _planner())
    door_cells = np.array(
        [[column, row] for row in range(DOOR_ROWS.start, DOOR_ROWS.stop) for column in range(52, 69)]
    )
    layers.glass.clear_cells(door_cells)  # the jambs' marks lie outside it and stay
    layers.apply_glass()
    assert not reachable(_planner(), layers.grid(), START, GOAL)
