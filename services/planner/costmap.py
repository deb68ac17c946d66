"""A layered costmap in the spirit of nav2_costmap_2d: static and obstacle layers, then inflation.

Cost values are Nav2's (``nav2_costmap_2d/cost_values.hpp``): 0 free, 1..252 inflated, 253 inscribed
(the robot's centre here means its footprint certainly touches an obstacle), 254 lethal, 255 unknown.

- Static layer: the occupancy map; -1 -> unknown, ``>= lethal_threshold`` -> lethal, else free.
- Obstacle layer: lidar endpoints within ``obstacle_max_range_m`` are marked lethal, and the cells a beam
  crossed on its way (Bresenham raytrace up to the hit or ``raytrace_max_range_m``) are cleared.
- Glass, invisible to the lidar, enters through the static layer: the planner's glass memory
  (:mod:`services.planner.glass_memory`, a probabilistic sonar model) is folded into the map it gives
  :meth:`LayeredCostmap.set_static_map`, so the lidar's clearing never erases it.
- Layers combine by maximum, skipping a layer's unknown cells; a known layer cell overrides unknown
  (``updateWithMax`` in nav2 ``costmap_layer.cpp``), so raytracing through unmapped space frees it.
- Inflation (nav2_costmap_2d ``inflation_layer.cpp``, ``computeCost``): at distance ``d`` from the
  nearest lethal cell, 254 at ``d = 0``, 253 for ``d <= inscribed_radius``, else
  ``int(252 * exp(-cost_scaling_factor * (d - inscribed_radius)))`` out to ``inflation_radius``.
  Unknown cells keep 255 unless the inflated cost is at least inscribed (``inflate_unknown: false``).

The costmap never decides what unknown means for motion: planners refuse 255 unless told to allow it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from services.planner.distance_transform import bounds_of, squared_distance_to_marks
from services.planner.grid_frame import GridFrame
from services.planner.grid_lines import ray_cells
from services.planner.occupancy_map import OCC_UNKNOWN, OccupancyMap
from shared.world import ROBOT_LENGTH_M, ROBOT_WIDTH_M

FREE_SPACE = 0
MAX_NON_OBSTACLE = 252
INSCRIBED_INFLATED_OBSTACLE = 253
LETHAL_OBSTACLE = 254
NO_INFORMATION = 255


@dataclass(frozen=True)
class CostmapParams:
    """Footprint, inflation and sensor ranges; defaults follow Nav2's example parameters."""

    robot_length_m: float = ROBOT_LENGTH_M
    robot_width_m: float = ROBOT_WIDTH_M
    inflation_radius_m: float = 0.55
    cost_scaling_factor: float = 3.0
    #: Static-map occupancy at or above this is lethal.
    lethal_threshold: int = 100
    obstacle_max_range_m: float = 2.5
    raytrace_max_range_m: float = 3.0
    #: A sonar reading with no echo (``>= max_range`` or +inf) clears its whole cone.
    range_clear_on_max_reading: bool = True

    def __post_init__(self) -> None:
        for name in ("robot_length_m", "robot_width_m", "cost_scaling_factor"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value}")
        for name in ("inflation_radius_m", "obstacle_max_range_m", "raytrace_max_range_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a non-negative number, got {value}")
        if not (1 <= self.lethal_threshold <= 100):
            raise ValueError(f"lethal_threshold must be in 1..100, got {self.lethal_threshold}")

    @property
    def inscribed_radius_m(self) -> float:
        """Radius of the largest circle inside the rectangular footprint (centred on base_link)."""
        return 0.5 * min(self.robot_length_m, self.robot_width_m)

    @property
    def circumscribed_radius_m(self) -> float:
        return 0.5 * math.hypot(self.robot_length_m, self.robot_width_m)


def inflation_cost(
    distance_m: np.ndarray | float, inscribed_radius_m: float, cost_scaling_factor: float
) -> np.ndarray:
    """Nav2's ``InflationLayer::computeCost`` for distances in metres (no inflation-radius cut-off).

    254 at distance 0, 253 within the inscribed radius, else ``floor(252 * exp(-k * (d - r_inscribed)))``.
    """
    d = np.asarray(distance_m, dtype=float)
    decay = np.floor(MAX_NON_OBSTACLE * np.exp(-cost_scaling_factor * (d - inscribed_radius_m)))
    # A hair of tolerance so a cell centre exactly on the inscribed circle (3 * 0.05 vs 0.15) is inscribed.
    inscribed = d <= inscribed_radius_m + 1e-9
    cost = np.where(inscribed, INSCRIBED_INFLATED_OBSTACLE, np.minimum(decay, MAX_NON_OBSTACLE))
    return np.where(d == 0.0, LETHAL_OBSTACLE, cost).astype(np.uint8)


def occupancy_from_costs(costs: np.ndarray) -> np.ndarray:
    """Costs as OccupancyGrid values for display (nav2 ``Costmap2DPublisher`` translation table)."""
    table = np.empty(256, dtype=np.int8)
    table[0] = 0
    table[1:253] = (1 + (97 * (np.arange(1, 253) - 1)) // 251).astype(np.int8)
    table[INSCRIBED_INFLATED_OBSTACLE] = 99
    table[LETHAL_OBSTACLE] = 100
    table[NO_INFORMATION] = -1
    return table[np.asarray(costs, dtype=np.uint8)]


@functools.lru_cache(maxsize=8)
def footprint_outline(length_m: float, width_m: float, spacing_m: float) -> np.ndarray:
    """Points ``(M, 2)`` along a rectangle centred on base_link, no more than ``spacing_m`` apart.

    Cached, read-only: the collision check asks for the same outline at every control tick (measurement
    75)."""
    hx, hy = 0.5 * length_m, 0.5 * width_m
    corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy], [hx, hy]])
    points = []
    for a, b in zip(corners[:-1], corners[1:], strict=True):
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / spacing_m))
        points.append(a + (b - a) * (np.arange(n) / n)[:, None])
    outline = np.concatenate(points)
    outline.flags.writeable = False
    return outline


@dataclass(frozen=True, eq=False)
class CostGrid:
    """An immutable snapshot of master costs (uint8, ``costs[iy, ix]``) on a :class:`GridFrame`."""

    frame: GridFrame
    costs: np.ndarray

    def cost_at(self, x: float, y: float) -> int:
        """Cost of the cell under a world point; :data:`NO_INFORMATION` off the grid."""
        ix, iy = self.frame.world_to_cell(x, y)
        return int(self.costs[iy, ix]) if self.frame.in_bounds(ix, iy) else NO_INFORMATION

    def costs_at(self, points_xy: np.ndarray) -> np.ndarray:
        """Costs under ``(N, 2)`` world points; :data:`NO_INFORMATION` off the grid."""
        cells = self.frame.world_to_cells(points_xy)
        out = np.full(len(cells), NO_INFORMATION, dtype=np.uint8)
        ok = self.frame.cells_in_bounds(cells)
        out[ok] = self.costs[cells[ok, 1], cells[ok, 0]]
        return out

    def downsampled(self, factor: int) -> CostGrid:
        """A coarser grid whose cells cover ``factor x factor`` cells, conservatively (nav2 Smac's
        ``downsample_costmap``): a coarse cell takes the highest known cost under it; it is unknown only
        if that cost is below inscribed and some cell under it is unknown. Ragged edges count as lethal.
        """
        if factor < 1:
            raise ValueError(f"downsampling factor must be a positive integer, got {factor}")
        if factor == 1:
            return self
        h, w = self.costs.shape
        ch, cw = -(-h // factor), -(-w // factor)
        padded = np.full((ch * factor, cw * factor), LETHAL_OBSTACLE, dtype=np.uint8)
        padded[:h, :w] = self.costs
        blocks = padded.reshape(ch, factor, cw, factor)
        unknown = blocks == NO_INFORMATION
        known_max = np.where(unknown, 0, blocks).max(axis=(1, 3))
        any_unknown = unknown.any(axis=(1, 3))
        coarse = np.where(any_unknown & (known_max < INSCRIBED_INFLATED_OBSTACLE), NO_INFORMATION, known_max)
        frame = GridFrame(self.frame.resolution_m * factor, self.frame.origin, cw, ch)
        return CostGrid(frame, coarse.astype(np.uint8))

    def footprint_costs(
        self, poses: np.ndarray, length_m: float = ROBOT_LENGTH_M, width_m: float = ROBOT_WIDTH_M
    ) -> np.ndarray:
        """Highest known cost under the rectangular footprint's outline at each ``(N, 3)`` pose.

        Like nav2 ``FootprintCollisionChecker::footprintCost``: the outline, not the inside, is checked
        (the inside was checked at earlier poses). An outline leaving the grid is lethal; unknown cells do
        not count unless the whole outline is unknown, then the result is :data:`NO_INFORMATION`.
        """
        poses = np.asarray(poses, dtype=float).reshape(-1, 3)
        outline = footprint_outline(length_m, width_m, 0.5 * self.frame.resolution_m)
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        wx = poses[:, 0:1] + c * outline[:, 0] - s * outline[:, 1]
        wy = poses[:, 1:2] + s * outline[:, 0] + c * outline[:, 1]
        cells = self.frame.world_to_cells(np.stack([wx.ravel(), wy.ravel()], axis=1))
        on_grid = self.frame.cells_in_bounds(cells)
        # Off the grid is lethal; unknown (-1 here) counts only when the whole outline is unknown.
        known = np.full(len(cells), LETHAL_OBSTACLE, dtype=np.int16)
        costs = self.costs[cells[on_grid, 1], cells[on_grid, 0]].astype(np.int16)
        known[on_grid] = np.where(costs == NO_INFORMATION, -1, costs)
        known = known.reshape(wx.shape)
        worst = known.max(axis=1)
        return np.where(worst < 0, NO_INFORMATION, worst).astype(np.uint8)


def laser_scan_points(
    sensor_pose: tuple[float, float, float],
    angle_min_rad: float,
    angle_increment_rad: float,
    ranges_m: np.ndarray,
    range_min_m: float,
    range_max_m: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Turn a LaserScan into ``(endpoints (N, 2), hits (N,))`` for :meth:`LayeredCostmap.update_with_scan`.

    ``sensor_pose`` is the lidar's pose (lidar_link) in the map frame; endpoints come out in the map frame.

    Readings in ``[range_min, range_max)`` are hits. +inf or ``>= range_max`` means no return: the
    endpoint sits at ``range_max`` and only clears. NaN, -inf and readings below ``range_min`` carry no
    information and are dropped (REP 117).
    """
    ranges = np.asarray(ranges_m, dtype=float).ravel()
    angles = sensor_pose[2] + angle_min_rad + angle_increment_rad * np.arange(len(ranges))
    no_return = (ranges == np.inf) | (np.isfinite(ranges) & (ranges >= range_max_m))
    hit = np.isfinite(ranges) & (ranges >= range_min_m) & (ranges < range_max_m)
    keep = hit | no_return
    reach = np.where(no_return, range_max_m, ranges)[keep]
    endpoints = np.stack(
        [sensor_pose[0] + reach * np.cos(angles[keep]), sensor_pose[1] + reach * np.sin(angles[keep])], axis=1
    )
    return endpoints, hit[keep]


class LayeredCostmap:
    """Static + obstacle layers over one grid, combined and inflated on demand.

    Sensor updates only touch their layer; :meth:`grid` recombines and inflates when something changed
    and otherwise returns the cached snapshot, so it is cheap to call every control cycle. It inflates
    again only round the cells whose combined cost changed (nav2's update bounds): a scan changes the
    few metres the lidar sees, and in a fleet each planner folds one in ten times a second.
    """

    def __init__(self, static_map: OccupancyMap, params: CostmapParams | None = None) -> None:
        self.params = params or CostmapParams()
        self._cached: CostGrid | None = None
        #: The combined costs the last snapshot was inflated from (None: inflate the whole grid next).
        self._inflated_from: np.ndarray | None = None
        self._last: CostGrid | None = None
        self.set_static_map(static_map)

    @property
    def frame(self) -> GridFrame:
        return self._frame

    @property
    def static_layer(self) -> np.ndarray:
        return self._static

    @property
    def obstacle_layer(self) -> np.ndarray:
        return self._obstacle

    def set_static_map(self, static_map: OccupancyMap) -> None:
        """Adopt a (new) map. Dynamic layers survive if the grid geometry is unchanged."""
        same_grid = getattr(self, "_frame", None) == static_map.frame
        self._frame = static_map.frame
        self._static = self._static_layer_of(static_map)
        if not same_grid:
            self._obstacle = np.full(static_map.data.shape, NO_INFORMATION, dtype=np.uint8)
            self._inflated_from = None
        self._cached = None

    def grid_over(self, static_map: OccupancyMap) -> CostGrid:
        """The inflated grid this costmap would give over another static map of the same grid, its sensor
        layers as they are; the costmap itself is left as it was (a what-if, inflated whole)."""
        if static_map.frame != self._frame:
            raise ValueError("grid_over needs a static map on the costmap's own grid")
        master = self._merged(self._static_layer_of(static_map))
        return _snapshot(self._frame, inflate(master, self._frame.resolution_m, self.params))

    def _static_layer_of(self, static_map: OccupancyMap) -> np.ndarray:
        data = static_map.data
        static = np.full(data.shape, FREE_SPACE, dtype=np.uint8)
        static[data >= self.params.lethal_threshold] = LETHAL_OBSTACLE
        static[data == OCC_UNKNOWN] = NO_INFORMATION
        return static

    def set_params(self, params: CostmapParams) -> None:
        """New settings (a runtime parameter change): the layers stay, the next :meth:`grid` inflates anew."""
        self.params = params
        self._cached = None
        self._inflated_from = None

    def clear(self) -> None:
        """Forget everything the sensors said (nav2 ``clearEntirely`` of the dynamic layers)."""
        self._obstacle.fill(NO_INFORMATION)
        self._cached = None

    def update_with_scan(
        self, sensor_xy: tuple[float, float], endpoints_xy: np.ndarray, hits: np.ndarray | None = None
    ) -> None:
        """Raytrace-clear then mark one lidar scan (see :func:`laser_scan_points` to build the inputs).

        ``endpoints_xy`` are beam ends in the map frame; ``hits[i]`` False means beam ``i`` found nothing
        (only clears). Marking happens after clearing, so this scan's own hits are kept.
        """
        endpoints = np.asarray(endpoints_xy, dtype=float).reshape(-1, 2)
        hit = np.ones(len(endpoints), dtype=bool) if hits is None else np.asarray(hits, dtype=bool).ravel()
        if len(hit) != len(endpoints):
            raise ValueError(f"hits has {len(hit)} entries for {len(endpoints)} endpoints")
        finite = np.all(np.isfinite(endpoints), axis=1)
        endpoints, hit = endpoints[finite], hit[finite]
        if len(endpoints) == 0:
            return
        origin = np.asarray(sensor_xy, dtype=float).reshape(2)
        start_cell = self._frame.world_to_cells(origin[None, :])[0]
        if not self._frame.in_bounds(int(start_cell[0]), int(start_cell[1])):
            return  # nav2 also refuses to raytrace from a sensor off the map
        vectors = endpoints - origin
        lengths = np.hypot(vectors[:, 0], vectors[:, 1])
        clip = np.minimum(1.0, self.params.raytrace_max_range_m / np.maximum(lengths, 1e-12))
        clear_ends = self._frame.world_to_cells(origin + vectors * clip[:, None])
        cells, ray = ray_cells(start_cell, clear_ends, include_end=False)
        # A beam that hit nothing, or was cut short by the raytrace range, also clears its last cell.
        open_ended = ~hit | (clip < 1.0)
        cells = np.concatenate([cells, clear_ends[open_ended]])
        self._set_cells(self._obstacle, cells, FREE_SPACE)
        marks = hit & (lengths <= self.params.obstacle_max_range_m)
        self._set_cells(self._obstacle, self._frame.world_to_cells(endpoints[marks]), LETHAL_OBSTACLE)

    def clear_around(self, xy: tuple[float, float], radius_m: float) -> None:
        """Forget what the sensors said within ``radius_m`` of a point."""
        self.clear_cells(self._frame.cells_within(xy, radius_m))

    def clear_cells(self, cells: np.ndarray) -> None:
        """Forget what the sensors said in ``cells`` (``(N, 2)``; nav2's region clears)."""
        self._set_cells(self._obstacle, cells, NO_INFORMATION)

    def clear_footprint(self, pose: tuple[float, float, float]) -> None:
        """Free the cells under the robot in the dynamic layers (nav2 ``footprint_clearing_enabled``)."""
        p = self.params
        self._set_cells(
            self._obstacle,
            self._frame.cells_under_rectangle(pose, p.robot_length_m, p.robot_width_m),
            FREE_SPACE,
        )

    def combined_costs(self) -> np.ndarray:
        """Layers merged by maximum, before inflation (unknown in a layer defers to the others)."""
        return self._merged(self._static)

    def _merged(self, static: np.ndarray) -> np.ndarray:
        master = static.copy()
        layer = self._obstacle
        known = layer != NO_INFORMATION
        take = known & ((master == NO_INFORMATION) | (master < layer))
        master[take] = layer[take]
        return master

    def grid(self) -> CostGrid:
        """The inflated master costmap, recomputed only after a change."""
        if self._cached is None:
            master = self.combined_costs()
            self._cached = self._inflated(master)
            self._inflated_from, self._last = master, self._cached
        return self._cached

    def _inflated(self, master: np.ndarray) -> CostGrid:
        """``master`` inflated: the last snapshot with the region round the changed cells inflated anew.

        A cell's inflated cost depends on the combined costs within the inflation radius of it, so only
        cells within ``reach`` (more than the radius) of a changed cell can change, and inflating a
        window ``reach`` wider still sees every lethal cell that matters to them.
        """
        previous, last = self._inflated_from, self._last
        if previous is None or last is None:
            return _snapshot(self._frame, inflate(master, self._frame.resolution_m, self.params))
        changed = master != previous
        reach = int(math.ceil(self.params.inflation_radius_m / self._frame.resolution_m)) + 1
        bounds = bounds_of(changed, reach)
        if bounds is None:
            return last
        rows, columns = bounds
        height, width = master.shape
        window_rows = slice(max(0, rows.start - reach), min(height, rows.stop + reach))
        window_columns = slice(max(0, columns.start - reach), min(width, columns.stop + reach))
        part = inflate(master[window_rows, window_columns], self._frame.resolution_m, self.params)
        costs = last.costs.copy()
        costs[rows, columns] = part[
            rows.start - window_rows.start : rows.stop - window_rows.start,
            columns.start - window_columns.start : columns.stop - window_columns.start,
        ]
        return _snapshot(self._frame, costs)

    def _set_cells(self, layer: np.ndarray, cells: np.ndarray, value: int) -> None:
        cells = np.asarray(cells).reshape(-1, 2)
        if len(cells) == 0:
            return
        cells = cells[self._frame.cells_in_bounds(cells)]
        layer[cells[:, 1], cells[:, 0]] = value
        self._cached = None


def _snapshot(frame: GridFrame, costs: np.ndarray) -> CostGrid:
    costs.flags.writeable = False
    return CostGrid(frame, costs)


def inflate(master: np.ndarray, resolution_m: float, params: CostmapParams) -> np.ndarray:
    """Inflate lethal cells of a combined costmap (nav2 ``InflationLayer``; see the module docstring)."""
    radius_cells = params.inflation_radius_m / resolution_m
    # Cells whose centre is within the inflation radius of a lethal cell centre (squared, in cells).
    max_d2 = int(math.floor(radius_cells * radius_cells + 1e-6))
    d2 = squared_distance_to_marks(master == LETHAL_OBSTACLE, math.sqrt(max_d2))
    # One cost per possible squared cell distance: a lookup table instead of exp on every cell.
    table_d2 = np.arange(max_d2 + 2)
    table = inflation_cost(
        np.sqrt(table_d2) * resolution_m, params.inscribed_radius_m, params.cost_scaling_factor
    )
    table[max_d2 + 1] = FREE_SPACE
    inflated = table[np.minimum(d2, max_d2 + 1)]
    out = np.where(master == NO_INFORMATION, master, np.maximum(master, inflated))
    unknown_inside = (master == NO_INFORMATION) & (inflated >= INSCRIBED_INFLATED_OBSTACLE)
    out[unknown_inside] = inflated[unknown_inside]
    return out.astype(np.uint8)
