"""An empty rectangular room's inflated costmap, for the planner's unit tests."""

from __future__ import annotations

from services.planner.costmap import CostGrid, CostmapParams, LayeredCostmap
from services.planner.rasterize import map_from_world
from shared.world import parse_world


def room_grid(
    width_m: float, walls: list | None = None, start: tuple[float, float, float] = (0.5, 1.5, 0.0)
) -> CostGrid:
    """A ``width_m`` x 3 m room with ``walls`` (``[[x0, y0], [x1, y1]]`` each), inflated as the planner does."""
    world = parse_world(
        {
            "name": "room",
            "bounds": [0.0, 0.0, width_m, 3.0],
            "walls": walls or [],
            "robot": {"start": list(start)},
        }
    )
    return LayeredCostmap(map_from_world(world), CostmapParams()).grid()
