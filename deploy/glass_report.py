"""How true the planner's glass memory is: cells marked away from every real pane, and pane length found.

After a trial (or a demo) the planner's glass memory file (``glass_memory_file``: the sonar layer and its
grid's geometry) is compared with the world's panes: a cell marked as glass more than
``tolerance_m`` from every pane is false glass (it may box a robot in); a point of a pane within
``tolerance_m`` of a mark is found. Reads the file as data; no planner code is imported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shared.geometry import distances_to_segment
from shared.world import World

#: The sonar layer's value for a cell marked as glass.
GLASS_MARK = 254
#: Marks this close to a pane count as the pane (two cells at 5 cm).
TOLERANCE_M = 0.1
#: Points per metre of pane when measuring how much of it was found.
SAMPLES_PER_M = 50


@dataclass(frozen=True, slots=True)
class GlassReport:
    false_glass_cells: int
    #: Fraction of the world's pane length within the tolerance of a mark (NaN: the world has no glass).
    glass_coverage: float
    marked_cells: int


@dataclass(frozen=True)
class GlassMarks:
    """The marked cells of a glass memory, in the world, judged against the world's panes."""

    world: World
    #: ``(N, 2)`` centres of the marked cells.
    xy: np.ndarray
    #: ``N`` booleans: the mark lies more than the tolerance from every pane.
    false: np.ndarray
    tolerance_m: float = TOLERANCE_M

    @property
    def true_xy(self) -> np.ndarray:
        return self.xy[~self.false]

    @property
    def false_xy(self) -> np.ndarray:
        return self.xy[self.false]

    def report(self) -> GlassReport:
        marks = self.xy
        panes = [(np.asarray(a, dtype=float), np.asarray(b, dtype=float)) for a, b in self.world.glass]
        false_cells = int(np.count_nonzero(self.false))
        if not panes:
            return GlassReport(false_cells, math.nan, len(marks))
        found = total = 0
        for a, b in panes:
            samples = max(2, math.ceil(float(np.hypot(*(b - a))) * SAMPLES_PER_M))
            points = a + np.linspace(0.0, 1.0, samples)[:, None] * (b - a)
            total += samples
            if len(marks):
                gaps = np.min(
                    np.hypot(points[:, None, 0] - marks[None, :, 0], points[:, None, 1] - marks[None, :, 1]),
                    axis=1,
                )
                found += int(np.count_nonzero(gaps <= self.tolerance_m))
        return GlassReport(false_cells, found / total, len(marks))


def glass_marks(
    layer: np.ndarray,
    resolution_m: float,
    origin_xy: tuple[float, float],
    world: World,
    tolerance_m: float = TOLERANCE_M,
) -> GlassMarks:
    """The marks of a sonar layer (``(height, width)``, row ``iy`` column ``ix``) against ``world``'s glass."""
    iy, ix = np.nonzero(np.asarray(layer) == GLASS_MARK)
    xy = np.stack(
        [origin_xy[0] + (ix + 0.5) * resolution_m, origin_xy[1] + (iy + 0.5) * resolution_m], axis=1
    )
    nearest = np.full(len(xy), np.inf)
    for a, b in world.glass:
        nearest = np.minimum(nearest, distances_to_segment(xy, np.asarray(a), np.asarray(b)))
    return GlassMarks(world, xy, nearest > tolerance_m, tolerance_m)


def glass_report(
    layer: np.ndarray,
    resolution_m: float,
    origin_xy: tuple[float, float],
    world: World,
    tolerance_m: float = TOLERANCE_M,
) -> GlassReport:
    """Compare a sonar layer with ``world``'s glass."""
    return glass_marks(layer, resolution_m, origin_xy, world, tolerance_m).report()


def read_glass_marks(path: Path, world: World) -> GlassMarks | None:
    """The marks of a planner's glass memory file; None when there is none (yet) or it is unreadable."""
    try:
        with np.load(path, allow_pickle=False) as stored:
            layer = np.array(stored["sonar"])
            resolution = float(stored["resolution"])
            origin = tuple(float(v) for v in stored["origin"][:2])
    except (OSError, KeyError, ValueError):
        return None
    return glass_marks(layer, resolution, (origin[0], origin[1]), world)
