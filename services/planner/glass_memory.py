"""Glass: what the sonar alone has found, and where a pane it has only partly seen may go on unseen.

The robot's one sonar looks forward through a 0.5 rad cone, so a pane is seen only where the robot
happened to face it. Driving round the end of a partly seen pane, the part never faced (the last
0.3 m in the glass room) is open floor on every layer, and the path cuts close to it. Glass memory
keeps the sonar's own range layer (marks from echoes the lidar cannot explain, see
:mod:`services.planner.sonar_fusion`; clearing of the cones it looked through) and treats a cell as
glass when the sonar marked it, or when the sonar has never looked at it and it lies within
``suspicion_radius_m`` of a mark: a pane probably goes on, and the robot may pass there only once its
sonar has looked. Cells the robot's footprint has covered are known to be free.

The node folds the glass into the costmap's static layer (it is as good as a wall until cleared), so
the lidar's clearing never erases it; a recovery or a clear request forgets it.
"""

from __future__ import annotations

import math

import numpy as np

from services.planner.costmap import LETHAL_OBSTACLE, NO_INFORMATION, CostmapParams, LayeredCostmap
from services.planner.distance_transform import squared_distance_to_marks
from services.planner.grid_frame import GridFrame
from services.planner.occupancy_map import OCC_FREE, OccupancyMap


class GlassMemory:
    """The sonar's marks and clearings on one grid, and the glass they imply."""

    def __init__(self, frame: GridFrame, params: CostmapParams, suspicion_radius_m: float = 0.5) -> None:
        if not (math.isfinite(suspicion_radius_m) and suspicion_radius_m >= 0):
            raise ValueError(f"suspicion_radius_m must be a non-negative number, got {suspicion_radius_m}")
        self.frame = frame
        self.suspicion_radius_m = suspicion_radius_m
        blank = OccupancyMap(frame.resolution_m, frame.origin, np.full(frame.shape, OCC_FREE, dtype=np.int8))
        self._sonar = LayeredCostmap(blank, params)

    @property
    def sonar_layer(self) -> np.ndarray:
        """Per cell: 254 marked by an echo, 0 looked through, 255 never looked at."""
        return self._sonar.range_layer

    def add_reading(
        self,
        sensor_pose: tuple[float, float, float],
        range_m: float,
        field_of_view_rad: float,
        min_range_m: float,
        max_range_m: float,
    ) -> None:
        """An echo the lidar cannot explain (or no echo): mark the arc, clear the cone short of it."""
        self._sonar.update_with_range(sensor_pose, range_m, field_of_view_rad, min_range_m, max_range_m)

    def add_clear_view(
        self, sensor_pose: tuple[float, float, float], clear_to_m: float, field_of_view_rad: float, min_range_m: float
    ) -> None:
        """The sonar saw nothing but what the lidar sees: nothing in the cone before ``clear_to_m``."""
        # A reading with no echo out to a maximum range of clear_to_m clears that far and marks nothing.
        self._sonar.update_with_range(sensor_pose, clear_to_m, field_of_view_rad, min_range_m, clear_to_m)

    def observe_footprint(self, pose: tuple[float, float, float]) -> None:
        """Where the robot stands there is no glass."""
        self._sonar.clear_footprint(pose)

    def observe_turning_circle(self, pose: tuple[float, float, float]) -> None:
        """Within reach of the robot turning in place, suspect nothing unseen (marks stay marks).

        A robot that stopped facing a pane has the pane's marks ahead and, beside the sonar's narrow cone,
        cells it never looked at within ``suspicion_radius_m`` of them: suspected glass within reach of
        its front corners. It could then neither turn (a corner sweeps into them) nor back away (the
        outline the follower checks lies half a cell outside the cells its footprint cleared), and every
        recovery ended the same way. The node calls this when a task starts, with the robot standing
        still, and never while driving: suspicion keeps a moving robot off the unseen end of a pane.
        """
        x, y, _ = pose
        reach = self._sonar.params.circumscribed_radius_m + 1.5 * self.frame.resolution_m
        self._sonar.free_unseen_range_around((x, y), reach)

    def clear(self) -> None:
        self._sonar.clear()

    def clear_around(self, xy: tuple[float, float], radius_m: float) -> None:
        """Forget marks and looks within ``radius_m`` of a point; glass found farther away stays known."""
        self._sonar.clear_around(xy, radius_m)

    def restore(self, layer: np.ndarray) -> None:
        """Adopt a sonar layer kept from before (see :mod:`services.planner.glass_store`)."""
        if layer.shape != self.frame.shape:
            raise ValueError(f"a sonar layer of shape {layer.shape} does not fit the grid {self.frame.shape}")
        self._sonar.range_layer[...] = layer

    def glass_mask(self) -> np.ndarray:
        """Boolean ``(height, width)``: marked by the sonar, or unlooked-at within the suspicion radius."""
        layer = self._sonar.range_layer
        marks = layer == LETHAL_OBSTACLE
        if self.suspicion_radius_m <= 0 or not marks.any():
            return marks
        radius_cells = self.suspicion_radius_m / self.frame.resolution_m
        near = squared_distance_to_marks(marks, radius_cells) <= radius_cells * radius_cells
        return marks | (near & (layer == NO_INFORMATION))
