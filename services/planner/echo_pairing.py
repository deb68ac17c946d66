"""Where on its arc an echo came from, told by an earlier echo of the same surface heard from elsewhere.

One echo says only that the nearest surface in the cone lies somewhere on the arc at its range. A flat
surface that made two echoes, heard from ``c1`` at ``r1`` and from ``c2`` at ``r2``, is a line tangent to
both arcs on their far side: with ``n`` its unit normal pointing away from the sensors, ``n . c1 + r1 =
n . c2 + r2``, so ``n . (c1 - c2) = r2 - r1``. Each bearing on the newer arc is the normal of one such
line (the line tangent there), so the bearings that satisfy the equation, give or take the ranges' noise,
are where on the arc the echo can have come from; the rest of the arc is open floor as far as this echo
can tell. A pane's end or a post (a point ``P``) fits nearly as well: the bearing the equation gives is
the bearing to ``P`` within ``d^2 / (2 r)`` of a metre along the arc, for a baseline ``d`` at range ``r``.

Head-on to a flat pane the equation allows the whole cone (moving straight at a surface tells nothing of
where across the cone it lies), and the echo keeps its whole arc, as it should: a pane straight ahead fills
it. Where the pane's normal points outside the cone (a pane beside the robot, at a slant), its nearest
point in the cone is where it crosses the cone's edge, and no line touching the arc made the echo: two
echoes are paired that way too (:func:`edge_sides`, :func:`edge_point_on_tangent_mask`), and the evidence
goes to the edge, not to the middle of the arc, which lies up to ``0.5 r sin(incidence)`` in front of the
pane. Driving dead straight at one heading, a pane crossing the edge and a line touching the arc give the
same ranges; the pairing then keeps both, and only a change of heading tells them apart.

Pure numpy: no grid, no bus. :mod:`services.planner.glass_memory` pairs each unexplained echo with the
recent ones (:class:`EchoPairing`).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

#: How far apart two echoes' sensors must be for their pairing to say where on the arc the newer came from
#: (below it the ranges' noise allows most of the cone), and at most (farther apart, two echoes more
#: often came from two different surfaces).
MIN_BASELINE_M = 0.15
MAX_BASELINE_M = 1.0
#: How far ``n . (c1 - c2)`` may miss ``r2 - r1``: the two ranges' noise (5 mm each), a cell's worth of
#: odometry drift between the two poses, and a pane's end standing in for a line.
TANGENT_TOLERANCE_M = 0.03
#: How far a line's point on a cone's edge may come nearer the sensor, entering the cone, and still count as the
#: nearest point there (the ranges' noise).
EDGE_SLACK_M = 0.01
#: How many of the latest unexplained echoes are kept to pair with.
RECENT_ECHOES = 40


@dataclass(frozen=True, slots=True)
class Echo:
    """An unexplained echo: the sensor's pose (map frame) and the range heard."""

    x: float
    y: float
    yaw: float
    range_m: float
    half_fov_rad: float


def tangent_bearing_mask(
    newer: Echo, older: Echo, bearings_rad: np.ndarray, tolerance_m: float = TANGENT_TOLERANCE_M
) -> np.ndarray:
    """Per bearing on ``newer``'s arc (relative to its axis): could a line tangent to both arcs touch there,
    with the touching point on ``older``'s arc inside ``older``'s cone?"""
    dx, dy = older.x - newer.x, older.y - newer.y
    normal = newer.yaw + np.asarray(bearings_rad, dtype=float)
    fits = np.abs(np.cos(normal) * dx + np.sin(normal) * dy - (newer.range_m - older.range_m)) <= tolerance_m
    off_older_axis = np.abs((normal - older.yaw + math.pi) % (2.0 * math.pi) - math.pi)
    return fits & (off_older_axis <= older.half_fov_rad)


def _edge_point(echo: Echo, side: int) -> np.ndarray:
    """The point of ``echo``'s arc on its cone's edge, ``side`` -1 (right) or +1 (left)."""
    angle = echo.yaw + side * echo.half_fov_rad
    return np.array([echo.x + echo.range_m * math.cos(angle), echo.y + echo.range_m * math.sin(angle)])


def _nearest_from_edge(echo: Echo, side: int, direction: np.ndarray) -> bool:
    """Whether a line along ``direction`` through ``echo``'s edge point on ``side`` has that point as its
    nearest within the cone: the line recedes from the sensor as it enters the cone."""
    inward = echo.yaw + side * echo.half_fov_rad - side * 0.5 * math.pi  # across the edge, toward the axis
    into_cone = direction * math.copysign(
        1.0, math.cos(inward) * direction[0] + math.sin(inward) * direction[1]
    )
    point = _edge_point(echo, side)
    away = point - np.array([echo.x, echo.y])
    return bool(into_cone @ away >= -EDGE_SLACK_M)


def _tangent_normals(echo: Echo, point: np.ndarray) -> list[np.ndarray]:
    """Unit normals of the lines through ``point`` tangent to ``echo``'s arc inside its cone."""
    dx, dy = point[0] - echo.x, point[1] - echo.y
    distance = math.hypot(dx, dy)
    if distance <= echo.range_m:
        return []
    spread = math.acos(echo.range_m / distance)
    normals = []
    for sign in (-1.0, 1.0):
        angle = math.atan2(dy, dx) + sign * spread
        if abs((angle - echo.yaw + math.pi) % (2.0 * math.pi) - math.pi) <= echo.half_fov_rad:
            normals.append(np.array([math.cos(angle), math.sin(angle)]))
    return normals


def edge_sides(newer: Echo, older: Echo) -> list[int]:
    """The edges of ``newer``'s cone (-1, +1) a straight surface may have crossed there to make both echoes:
    one that enters ``newer``'s cone at its edge point and recedes, and that ``older`` heard at its own
    edge the same way or where the surface is tangent to its arc."""
    sides = []
    for side in (-1, 1):
        point = _edge_point(newer, side)
        directions = []
        for other_side in (-1, 1):
            chord = _edge_point(older, other_side) - point
            length = float(np.hypot(*chord))
            if length > 1e-6 and _nearest_from_edge(older, other_side, -chord / length):
                directions.append(chord / length)
        directions += [np.array([-n[1], n[0]]) for n in _tangent_normals(older, point)]
        if any(_nearest_from_edge(newer, side, d) for d in directions):
            sides.append(side)
    return sides


def edge_point_on_tangent_mask(
    newer: Echo, older: Echo, bearings_rad: np.ndarray, tolerance_m: float = TANGENT_TOLERANCE_M
) -> np.ndarray:
    """Per bearing on ``newer``'s arc: could a line tangent there run through an edge point of ``older``'s
    arc, the nearest point of the line in ``older``'s cone?"""
    normal = newer.yaw + np.asarray(bearings_rad, dtype=float)
    nx, ny = np.cos(normal), np.sin(normal)
    rho = nx * newer.x + ny * newer.y + newer.range_m
    mask = np.zeros(normal.shape, dtype=bool)
    for side in (-1, 1):
        point = _edge_point(older, side)
        on_line = np.abs(nx * point[0] + ny * point[1] - rho) <= tolerance_m
        # The line's direction (-ny, nx), turned to enter older's cone at the point, must lead away from it.
        inward = older.yaw + side * older.half_fov_rad - side * 0.5 * math.pi
        toward_axis = -ny * math.cos(inward) + nx * math.sin(inward)
        away_x, away_y = point[0] - older.x, point[1] - older.y
        recedes = np.sign(toward_axis) * (-ny * away_x + nx * away_y) >= -EDGE_SLACK_M
        mask |= on_line & recedes & (toward_axis != 0.0)
    return mask


class EchoPairing:
    """The latest unexplained echoes, and which part of a new echo's arc they agree it came from.

    An echo no earlier one can place keeps only part of its evidence for now (see
    :mod:`services.planner.glass_memory`) and waits here unresolved: the first later echo that can place it
    resolves it, and the memory gives it the rest of its evidence where the two agree."""

    def __init__(self, recent: int = RECENT_ECHOES) -> None:
        self._recent: deque[_Kept] = deque(maxlen=recent)

    def clear(self) -> None:
        self._recent.clear()

    def where(
        self, echo: Echo, bearings_rad: np.ndarray, cell_half_angle_rad: np.ndarray
    ) -> np.ndarray | None:
        """Boolean per cell of ``echo``'s arc (its bearing and angular half width as seen from the sensor):
        where the echo may have come from, by the newest earlier echo that can say and agrees with it on
        some bearing; None when none can (the whole arc stays possible)."""
        for kept in reversed(self._recent):
            mask = placed_by(echo, kept.echo, bearings_rad, cell_half_angle_rad)
            if mask is not None:
                return mask
        return None

    def unresolved_near(self, echo: Echo) -> list[Echo]:
        """The kept echoes still unresolved that ``echo`` lies at a baseline to place, oldest first."""
        return [kept.echo for kept in self._recent if not kept.resolved and _useful_baseline(kept.echo, echo)]

    def resolved(self, echo: Echo) -> None:
        for kept in self._recent:
            if kept.echo is echo:
                kept.resolved = True

    def keep(self, echo: Echo, resolved: bool) -> None:
        self._recent.append(_Kept(echo, resolved))


@dataclass(slots=True)
class _Kept:
    echo: Echo
    resolved: bool


def _useful_baseline(a: Echo, b: Echo) -> bool:
    return MIN_BASELINE_M <= math.hypot(a.x - b.x, a.y - b.y) <= MAX_BASELINE_M


def placed_by(
    echo: Echo, other: Echo, bearings_rad: np.ndarray, cell_half_angle_rad: np.ndarray
) -> np.ndarray | None:
    """Where on ``echo``'s arc (per cell: bearing, angular half width) a surface that also made ``other``
    can touch it; None when the two lie too near or too far apart to tell, or agree on no bearing."""
    if not _useful_baseline(echo, other):
        return None
    baseline = math.hypot(other.x - echo.x, other.y - echo.y)
    bearings = np.asarray(bearings_rad, dtype=float)
    mask = tangent_bearing_mask(echo, other, bearings) | edge_point_on_tangent_mask(echo, other, bearings)
    turn = abs((echo.yaw - other.yaw + math.pi) % (2.0 * math.pi) - math.pi)
    reach = baseline + max(echo.range_m, other.range_m) * turn + TANGENT_TOLERANCE_M
    # Where a surface crosses a cone's edge, its echo moves with the cone; farther than the cone itself
    # moved, the two echoes came from two surfaces.
    sides = edge_sides(echo, other) if abs(echo.range_m - other.range_m) <= reach else []
    for side in sides:
        # The cells the cone's edge runs through on that side.
        mask |= side * bearings >= echo.half_fov_rad - 2.0 * np.asarray(cell_half_angle_rad)
    mask &= np.abs(bearings) < echo.half_fov_rad
    return mask if mask.any() else None
