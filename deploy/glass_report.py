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


def glass_report(
    layer: np.ndarray, resolution_m: float, origin_xy: tuple[float, float], world: World,
    tolerance_m: float = TOLERANCE_M,
) -> GlassReport:
    """Compare a sonar layer (``(height, width)``, row ``iy`` column ``ix``) with ``world``'s glass."""
    iy, ix = np.nonzero(np.asarray(layer) == GLASS_MARK)
    marks = np.stack([origin_xy[0] + (ix + 0.5) * resolution_m, origin_xy[1] + (iy + 0.5) * resolution_m], axis=1)
    panes = [(np.asarray(a, dtype=float), np.asarray(b, dtype=float)) for a, b in world.glass]
    if not panes:
        return GlassReport(len(marks), math.nan, len(marks))
    nearest = np.full(len(marks), np.inf)
    for a, b in panes:
        nearest = np.minimum(nearest, _distance_to_segment(marks, a, b))
    false_cells = int(np.count_nonzero(nearest > tolerance_m))
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
    try:
        with np.load(path, allow_pickle=False) as stored:
            layer = np.array(stored["sonar"])
            resolution = float(stored["resolution"])
            origin = tuple(float(v) for v in stored["origin"][:2])
    except (OSError, KeyError, ValueError):
        return None
    return glass_report(layer, resolution, (origin[0], origin[1]), world)


def _distance_to_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    length2 = float(ab @ ab)
    t = np.zeros(len(points)) if length2 == 0 else np.clip(((points - a) @ ab) / length2, 0.0, 1.0)
    closest = a + t[:, None] * ab
    return np.hypot(points[:, 0] - closest[:, 0], points[:, 1] - closest[:, 1])
