"""Where a grid of square cells sits in the map frame, and conversions between metres and cells.

The convention is ROS ``nav_msgs/OccupancyGrid``: ``origin`` is the pose of cell (0, 0)'s outer corner,
cell ``(ix, iy)`` covers ``[ix, ix+1) x [iy, iy+1)`` cell widths from it along the origin's axes, and
arrays are indexed ``array[iy, ix]`` (row-major, row 0 at the origin, so rows grow with y).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class GridFrame:
    """Geometry of a ``height x width`` grid: resolution and the origin pose ``(x, y, yaw)``."""

    resolution_m: float
    origin: tuple[float, float, float]
    width: int
    height: int

    def __post_init__(self) -> None:
        if not (math.isfinite(self.resolution_m) and self.resolution_m > 0):
            raise ValueError(f"resolution_m must be a positive number, got {self.resolution_m}")
        if self.width < 0 or self.height < 0:
            raise ValueError(f"grid size must be non-negative, got {self.width} x {self.height}")

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)``: the shape of arrays on this grid."""
        return (self.height, self.width)

    def _to_local(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ox, oy, yaw = self.origin
        dx, dy = x - ox, y - oy
        if yaw == 0.0:
            return dx, dy
        c, s = math.cos(yaw), math.sin(yaw)
        return c * dx + s * dy, -s * dx + c * dy

    def world_to_grid(self, points_xy: np.ndarray) -> np.ndarray:
        """Continuous grid coordinates (in cells, cell centres at ``i + 0.5``) of ``(N, 2)`` world points."""
        pts = np.asarray(points_xy, dtype=float).reshape(-1, 2)
        lx, ly = self._to_local(pts[:, 0], pts[:, 1])
        return np.stack([lx, ly], axis=1) / self.resolution_m

    def world_to_cells(self, points_xy: np.ndarray) -> np.ndarray:
        """Integer ``(ix, iy)`` of the cells holding ``(N, 2)`` world points; may lie outside the grid."""
        # A tiny epsilon keeps points that sit exactly on a cell edge (up to rounding) in the upper cell.
        return np.floor(self.world_to_grid(points_xy) + 1e-9).astype(np.int64)

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        """``(ix, iy)`` of the cell holding world point ``(x, y)``; may lie outside the grid."""
        ix, iy = self.world_to_cells(np.array([[x, y]]))[0]
        return int(ix), int(iy)

    def cells_to_world(self, cells_ixy: np.ndarray) -> np.ndarray:
        """World ``(x, y)`` of the centres of ``(N, 2)`` integer cells ``(ix, iy)``."""
        cells = np.asarray(cells_ixy, dtype=float).reshape(-1, 2)
        lx = (cells[:, 0] + 0.5) * self.resolution_m
        ly = (cells[:, 1] + 0.5) * self.resolution_m
        ox, oy, yaw = self.origin
        c, s = math.cos(yaw), math.sin(yaw)
        return np.stack([ox + c * lx - s * ly, oy + s * lx + c * ly], axis=1)

    def cell_to_world(self, ix: int, iy: int) -> tuple[float, float]:
        """World ``(x, y)`` of the centre of cell ``(ix, iy)``."""
        x, y = self.cells_to_world(np.array([[ix, iy]]))[0]
        return float(x), float(y)

    def in_bounds(self, ix: int, iy: int) -> bool:
        return 0 <= ix < self.width and 0 <= iy < self.height

    def cells_in_bounds(self, cells_ixy: np.ndarray) -> np.ndarray:
        """Boolean mask of the ``(N, 2)`` cells that lie on the grid."""
        cells = np.asarray(cells_ixy).reshape(-1, 2)
        return (
            (cells[:, 0] >= 0) & (cells[:, 0] < self.width) & (cells[:, 1] >= 0) & (cells[:, 1] < self.height)
        )

    def cells_around(self, points_xy: np.ndarray) -> np.ndarray:
        """On-grid cells ``(N, 2)`` of the box bounding some world points, one cell of margin."""
        cells = self.world_to_cells(points_xy)
        lo = np.maximum(cells.min(axis=0) - 1, 0)
        hi = np.minimum(cells.max(axis=0) + 1, [self.width - 1, self.height - 1])
        if np.any(hi < lo):
            return np.zeros((0, 2), dtype=np.int64)
        iy, ix = np.mgrid[lo[1] : hi[1] + 1, lo[0] : hi[0] + 1]
        return np.stack([ix.ravel(), iy.ravel()], axis=1)

    def window_around(self, xy: tuple[float, float], radius_m: float) -> tuple[slice, slice]:
        """Row and column slices of the box of cells bounding the circle of ``radius_m`` round a point,
        one cell of margin, clipped to the grid (empty when the circle lies off it)."""
        ix, iy = self.world_to_cell(*xy)
        reach = int(math.ceil(radius_m / self.resolution_m)) + 1
        rows = slice(min(max(iy - reach, 0), self.height), min(max(iy + reach + 1, 0), self.height))
        columns = slice(min(max(ix - reach, 0), self.width), min(max(ix + reach + 1, 0), self.width))
        return rows, columns

    def cells_within(self, xy: tuple[float, float], radius_m: float) -> np.ndarray:
        """On-grid cells ``(N, 2)`` whose centres lie within ``radius_m`` of a point."""
        x, y = xy
        cells = self.cells_around(np.array([[x - radius_m, y - radius_m], [x + radius_m, y + radius_m]]))
        centres = self.cells_to_world(cells)
        return cells[np.hypot(centres[:, 0] - x, centres[:, 1] - y) <= radius_m]

    def cells_in_square(self, xy: tuple[float, float], side_m: float, outside: bool = False) -> np.ndarray:
        """On-grid cells ``(N, 2)`` whose centres lie inside the axis-aligned square of side ``side_m``
        centred on a point, or (``outside``) every other cell: Nav2's clearing regions."""
        height, width = self.shape
        iy, ix = np.mgrid[0:height, 0:width]
        cells = np.stack([ix.ravel(), iy.ravel()], axis=1)
        centres = self.cells_to_world(cells)
        half = 0.5 * side_m
        inside = (np.abs(centres[:, 0] - xy[0]) <= half) & (np.abs(centres[:, 1] - xy[1]) <= half)
        return cells[~inside if outside else inside]

    def cells_under_rectangle(
        self, pose: tuple[float, float, float], length_m: float, width_m: float
    ) -> np.ndarray:
        """On-grid cells ``(N, 2)`` whose centres lie inside a ``length_m`` x ``width_m`` rectangle centred on
        ``pose`` and turned with its yaw (the robot's footprint)."""
        x, y, yaw = pose
        reach = 0.5 * math.hypot(length_m, width_m) + self.resolution_m
        cells = self.cells_around(np.array([[x - reach, y - reach], [x + reach, y + reach]]))
        if len(cells) == 0:
            return cells
        centres = self.cells_to_world(cells)
        c, s = math.cos(yaw), math.sin(yaw)
        fx = c * (centres[:, 0] - x) + s * (centres[:, 1] - y)
        fy = -s * (centres[:, 0] - x) + c * (centres[:, 1] - y)
        return cells[(np.abs(fx) <= 0.5 * length_m) & (np.abs(fy) <= 0.5 * width_m)]

    def cell_centres(self) -> tuple[np.ndarray, np.ndarray]:
        """World x and y of every cell centre, each shaped ``(height, width)``."""
        iy, ix = np.mgrid[0 : self.height, 0 : self.width]
        xy = self.cells_to_world(np.stack([ix.ravel(), iy.ravel()], axis=1))
        return xy[:, 0].reshape(self.shape), xy[:, 1].reshape(self.shape)
