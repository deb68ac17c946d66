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


def mark_centres(layer: np.ndarray, resolution_m: float, origin_xy: tuple[float, float]) -> np.ndarray:
    """World ``(x, y)`` of the marked cells of a sonar layer (``(height, width)``, row ``iy`` column ``ix``)."""
    iy, ix = np.nonzero(np.asarray(layer) == GLASS_MARK)
    return np.stack([origin_xy[0] + (ix + 0.5) * resolution_m, origin_xy[1] + (iy + 0.5) * resolution_m], axis=1)


def glass_report(
    layer: np.ndarray, resolution_m: float, origin_xy: tuple[float, float], world: World,
    tolerance_m: float = TOLERANCE_M,
) -> GlassReport:
    """Compare a sonar layer with ``world``'s glass."""
    marks = mark_centres(layer, resolution_m, origin_xy)
    return glass_report_of_marks(marks, _distance_to_panes(marks, world) > tolerance_m, world, tolerance_m)


def glass_report_of_marks(
    marks: np.ndarray, false: np.ndarray, world: World, tolerance_m: float = TOLERANCE_M
) -> GlassReport:
    panes = [(np.asarray(a, dtype=float), np.asarray(b, dtype=float)) for a, b in world.glass]
    false_cells = int(np.count_nonzero(false))
    if not panes:
        return GlassReport(false_cells, math.nan, len(marks))
    found = total = 0
    for a, b in panes:
        samples = max(2, math.ceil(float(np.hypot(*(b - a))) * SAMPLES_PER_M))
        points = a + np.linspace(0.0, 1.0, samples)[:, None] * (b - a)
        total += samples
        if len(marks):
            gaps = np.min(np.hypot(points[:, None, 0] - marks[None, :, 0], points[:, None, 1] - marks[None, :, 1]), axis=1)
            found += int(np.count_nonzero(gaps <= tolerance_m))
    return GlassReport(false_cells, found / total, len(marks))


def read_glass_memory(path: Path, world: World) -> GlassReport | None:
    """The report of a planner's glass memory file; None when there is none (yet) or it is unreadable."""
    marks = read_glass_marks(path, world)
    if marks is None:
        return None
    xy, false = marks
    return glass_report_of_marks(xy, false, world)


def read_glass_marks(path: Path, world: World) -> tuple[np.ndarray, np.ndarray] | None:
    """The marks ``(N, 2)`` of a planner's glass memory file and which are false (``N`` booleans)."""
    try:
        with np.load(path, allow_pickle=False) as stored:
            layer = np.array(stored["sonar"])
            resolution = float(stored["resolution"])
            origin = tuple(float(v) for v in stored["origin"][:2])
    except (OSError, KeyError, ValueError):
        return None
    xy = mark_centres(layer, resolution, (origin[0], origin[1]))
    return xy, _distance_to_panes(xy, world) > TOLERANCE_M


def _distance_to_panes(points: np.ndarray, world: World) -> np.ndarray:
    """Each point's distance to the nearest pane (inf without glass)."""
    nearest = np.full(len(points), np.inf)
    for a, b in world.glass:
        nearest = np.minimum(nearest, _distance_to_segment(points, np.asarray(a, float), np.asarray(b, float)))
    return nearest


def _distance_to_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    length2 = float(ab @ ab)
    t = np.zeros(len(points)) if length2 == 0 else np.clip(((points - a) @ ab) / length2, 0.0, 1.0)
    closest = a + t[:, None] * ab
    return np.hypot(points[:, 0] - closest[:, 0], points[:, 1] - closest[:, 1])
