"""The costmap as Nav2 scripts get it (``global_costmap/get_costmap``, ``local_costmap/get_costmap``)."""

from __future__ import annotations

import numpy as np

from services.planner.costmap import LETHAL_OBSTACLE, CostGrid
from services.planner.grid_frame import GridFrame
from services.planner.map_messages import nav2_costmap_message


def _grid() -> CostGrid:
    frame = GridFrame(resolution_m=0.1, origin=(-1.0, -2.0, 0.0), width=40, height=30)
    costs = np.zeros(frame.shape, dtype=np.uint8)
    costs[:, 0] = LETHAL_OBSTACLE  # a wall along x = -1
    costs[12, 25] = 200
    return CostGrid(frame, costs)


def test_the_global_costmap_is_the_whole_grid_row_major_from_the_origin() -> None:
    msg = nav2_costmap_message(_grid(), 12.5, "map", "global_costmap")
    meta = msg.metadata
    assert (meta.size_x, meta.size_y, meta.layer) == (40, 30, "global_costmap")
    assert abs(meta.resolution - 0.1) < 1e-9 and msg.header.frame_id == "map"
    assert (meta.origin.position.x, meta.origin.position.y) == (-1.0, -2.0)
    data = np.asarray(msg.data).reshape(30, 40)
    assert data[12, 25] == 200 and (data[:, 0] == LETHAL_OBSTACLE).all() and data.sum() == 200 + 254 * 30


def test_the_local_costmap_is_the_square_round_the_robot_cut_to_the_grid() -> None:
    # A 1 m square (10 cells) round a point in cell (25, 12): cells 21..30 x 8..17 (the centre lies
    # half a cell from the square's: ten cells cannot centre on one), origin at that corner.
    msg = nav2_costmap_message(_grid(), 0.0, "map", "local_costmap", window=(1.57, -0.73, 1.0))
    meta = msg.metadata
    assert (meta.size_x, meta.size_y) == (10, 10)
    assert np.isclose(meta.origin.position.x, -1.0 + 2.1) and np.isclose(meta.origin.position.y, -2.0 + 0.8)
    data = np.asarray(msg.data).reshape(10, 10)
    assert data[4, 4] == 200 and data.sum() == 200
    # An odd count is centred exactly: 1.1 m is 11 cells, 20..30 x 7..17 round cell (25, 12).
    odd = nav2_costmap_message(_grid(), 0.0, "map", "local_costmap", window=(1.57, -0.73, 1.1))
    assert (odd.metadata.size_x, odd.metadata.size_y) == (11, 11)
    assert np.asarray(odd.data).reshape(11, 11)[5, 5] == 200
    # Near the grid's edge the square is cut: it holds the wall column and starts at the origin.
    edge = nav2_costmap_message(_grid(), 0.0, "map", "local_costmap", window=(-0.95, -1.95, 1.0))
    assert (edge.metadata.size_x, edge.metadata.size_y) == (6, 6)
    assert edge.metadata.origin.position.x == -1.0
    assert (np.asarray(edge.data).reshape(6, 6)[:, 0] == LETHAL_OBSTACLE).all()
    # No robot pose: an empty square, with the grid's frame and resolution all the same.
    empty = nav2_costmap_message(_grid(), 0.0, "map", "local_costmap", window=(0.0, 0.0, 0.0))
    assert (empty.metadata.size_x, empty.metadata.size_y, len(empty.data)) == (0, 0, 0)
    assert np.isclose(empty.metadata.resolution, 0.1) and empty.header.frame_id == "map"
