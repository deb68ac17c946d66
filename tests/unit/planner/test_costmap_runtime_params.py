"""A runtime change of the planner's inflation (``zendock param set planner inflation_radius_m``) re-inflates
the costmap at once and keeps what the sensors marked."""

from __future__ import annotations

import numpy as np

from services.planner.costmap import FREE_SPACE, LayeredCostmap
from services.planner.occupancy_map import OCC_FREE, OccupancyMap
from services.planner.params import Params
from shared.parameters import ParameterTable


def test_a_new_inflation_radius_reinflates_and_keeps_the_obstacle_layer() -> None:
    params = Params()
    occupancy = OccupancyMap(0.05, (0.0, 0.0, 0.0), np.full((80, 80), OCC_FREE, dtype=np.int8))
    costmap = LayeredCostmap(occupancy, params.costmap_params())
    costmap.update_with_scan((0.5, 2.0), np.array([[2.0, 2.0]]))
    far = (2.0 + 0.5, 2.0)  # 0.5 m from the mark: inside the default 0.55 m inflation
    assert costmap.grid().cost_at(*far) > FREE_SPACE

    table = ParameterTable(params)
    table.on_set("inflation_radius_m", lambda _name, _value: costmap.set_params(params.costmap_params()))
    table.set("inflation_radius_m", 0.3)

    assert costmap.grid().cost_at(*far) == FREE_SPACE
    assert costmap.grid().cost_at(2.0, 2.0) > FREE_SPACE  # the mark is still there
