"""Build the occupancy map a lidar would make of a world file, without driving the robot around.

Everything opaque to the lidar is occupied: the outer walls on the bounds, inner walls, boxes and dock
bodies (filled, since nothing inside them is reachable). Glass is left out on purpose: the lidar sees
through it, so only the ultrasonic sensor keeps the robot off it at run time. Inside the bounds is
free, outside unknown. Segments are drawn with the 4-connected supercover so walls have no diagonal
gaps a planner could slip through.
"""

from __future__ import annotations

import math

import numpy as np

from services.planner.grid_frame import GridFrame
from services.planner.grid_lines import segment_cells
from services.planner.occupancy_map import OCC_FREE, OCC_OCCUPIED, OCC_UNKNOWN, OccupancyMap
from shared.world import DOCK_GEOMETRY, Box, World


def map_from_world(world: World, resolution_m: float = 0.05, padding_m: float = 0.5) -> OccupancyMap:
    """Rasterise ``world`` at ``resolution_m``, with ``padding_m`` of unknown around the bounds.

    The result is an ordinary :class:`OccupancyMap`; :func:`services.planner.occupancy_map.save_map`
    writes it in the map_server format.
    """
    if not (math.isfinite(resolution_m) and resolution_m > 0):
        raise ValueError(f"resolution_m must be a positive number, got {resolution_m}")
    if not (math.isfinite(padding_m) and padding_m >= 0):
        raise ValueError(f"padding_m must be a non-negative number, got {padding_m}")
    xmin, ymin, xmax, ymax = world.bounds
    # Rounded so the origin written to YAML reads as the number a person would type.
    origin = (round(xmin - padding_m, 9), round(ymin - padding_m, 9), 0.0)
    width = math.ceil((xmax + padding_m - origin[0]) / resolution_m - 1e-9)
    height = math.ceil((ymax + padding_m - origin[1]) / resolution_m - 1e-9)
    frame = GridFrame(resolution_m, origin, width, height)

    data = np.full(frame.shape, OCC_UNKNOWN, dtype=np.int8)
    cx, cy = frame.cell_centres()
    data[(cx > xmin) & (cx < xmax) & (cy > ymin) & (cy < ymax)] = OCC_FREE

    for box in list(world.boxes) + [DOCK_GEOMETRY.body_box(dock) for dock in world.docks]:
        data[_inside_box(box, cx, cy)] = OCC_OCCUPIED
    for a, b in world.opaque_segments():
        _draw_segment(data, frame, a, b)
    return OccupancyMap(resolution_m=resolution_m, origin=origin, data=data)


def _inside_box(box: Box, cx: np.ndarray, cy: np.ndarray) -> np.ndarray:
    """Cells whose centre lies inside the box (its corners run counter-clockwise, so insides are left)."""
    corners = box.corners()
    inside = np.ones(cx.shape, dtype=bool)
    for i in range(4):
        (x1, y1), (x2, y2) = corners[i], corners[(i + 1) % 4]
        inside &= (x2 - x1) * (cy - y1) - (y2 - y1) * (cx - x1) >= 0.0
    return inside


def _draw_segment(data: np.ndarray, frame: GridFrame, a: tuple[float, float], b: tuple[float, float]) -> None:
    grid = frame.world_to_grid(np.array([a, b]))
    cells = segment_cells(grid[0], grid[1])
    cells = cells[frame.cells_in_bounds(cells)]
    data[cells[:, 1], cells[:, 0]] = OCC_OCCUPIED
