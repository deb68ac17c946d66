"""How true the planner's glass memory is: cells marked away from every real pane, and panes found.

After a trial (or a demo) the planner's glass memory file (``glass_memory_file``: the sonar layer and its
grid's geometry) is compared with the world's panes: a cell marked as glass more than
``tolerance_m`` from every pane is false glass (it may box a robot in); a point of a pane within
``tolerance_m`` of a mark is found. Reads the file as data; no planner code is imported.

A robot heading for its dock points its sonar at a few of a room's panes only, so the share of all pane
length found says as much about the route as about the mapping. The sonar echoes the trial recorded tell
which panes the sonar actually heard (the nearest surface in the ping's cone was the pane): of those, the
share with a mark on them is what the mapping made of what it was given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shared.geometry import distances_to_segment
from shared.models.raycast import SegmentSet, distances_in_cone
from shared.world import World

#: The sonar layer's value for a cell marked as glass.
GLASS_MARK = 254
#: Marks this close to a pane count as the pane (two cells at 5 cm).
TOLERANCE_M = 0.1
#: Points per metre of pane when measuring how much of it was found.
SAMPLES_PER_M = 50
#: An echo is a pane's when its range is within this of the pane's nearest point in the ping's cone (the
#: range's noise is 5 mm; the rest allows for the recorded pose lagging the ping).
ECHO_MATCH_M = 0.05

#: One recorded sonar echo: ``(sensor_x, sensor_y, sensor_yaw, range_m, field_of_view_rad)``.
Echo = tuple[float, float, float, float, float]


@dataclass(frozen=True, slots=True)
class GlassReport:
    false_glass_cells: int
    #: Fraction of the world's pane length within the tolerance of a mark (NaN: the world has no glass).
    glass_coverage: float
    marked_cells: int
    #: Panes that returned at least one of the trial's echoes, and how many of those carry a mark (0 and 0
    #: when no echoes were given).
    panes_heard: int = 0
    panes_found: int = 0


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

    def report(self, echoes: Sequence[Echo] = ()) -> GlassReport:
        """The report; ``echoes`` (the trial's sonar echoes) add the panes heard and found among them."""
        marks = self.xy
        panes = [(np.asarray(a, dtype=float), np.asarray(b, dtype=float)) for a, b in self.world.glass]
        false_cells = int(np.count_nonzero(self.false))
        if not panes:
            return GlassReport(false_cells, math.nan, len(marks))
        heard = panes_heard(echoes, self.world)
        found_heard = sum(
            1
            for i in heard
            if len(marks) and distances_to_segment(marks, panes[i][0], panes[i][1]).min() <= self.tolerance_m
        )
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
        return GlassReport(false_cells, found / total, len(marks), len(heard), found_heard)


def panes_heard(echoes: Sequence[Echo], world: World) -> set[int]:
    """Indices (into ``world.glass``) of the panes that returned at least one of ``echoes``.

    A ping's echo comes from the nearest surface in its cone (as the simulator's ranger has it): the echo
    is a pane's when that surface is a pane and lies at the echo's range, give or take ``ECHO_MATCH_M``.
    """
    if not echoes or not world.glass:
        return set()
    opaque = world.opaque_segments()
    segments = SegmentSet(opaque + list(world.glass))
    heard: set[int] = set()
    for x, y, yaw, range_m, fov in echoes:
        if not 0.0 < fov < math.pi:  # a ranger that says it has no cone, or one wider than a half-plane
            continue
        distance = distances_in_cone((x, y), yaw, 0.5 * fov, segments)
        nearest = int(np.argmin(distance))
        if nearest >= len(opaque) and abs(float(distance[nearest]) - range_m) <= ECHO_MATCH_M:
            heard.add(nearest - len(opaque))
    return heard


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
