"""Where on its arc an echo came from, told by an earlier echo of the same surface: the pairing's geometry,
and what it makes of the glass memory's marks beside an oblique pane."""

from __future__ import annotations

import math

import numpy as np

from services.planner.costmap import CostmapParams
from services.planner.echo_pairing import Echo, EchoPairing, placed_by
from services.planner.glass_memory import GlassMemory
from services.planner.grid_frame import GridFrame
from shared.models.raycast import SegmentSet, nearest_in_cone

HALF_FOV = 0.25
BEARINGS = np.linspace(-HALF_FOV + 1e-3, HALF_FOV - 1e-3, 101)
CELL_HALF_ANGLE = np.full(BEARINGS.shape, 0.02)


def _echo(pane: tuple[tuple[float, float], tuple[float, float]], x: float, y: float, yaw: float) -> Echo:
    """The simulator's ranger at ``(x, y, yaw)``: the nearest point of the pane inside the cone."""
    range_m = nearest_in_cone((x, y), yaw, HALF_FOV, SegmentSet([pane]))
    assert math.isfinite(range_m), "the pane is not in the cone"
    return Echo(x, y, yaw, range_m, HALF_FOV)


def _touching_bearing(echo: Echo, pane: tuple[tuple[float, float], tuple[float, float]]) -> float:
    """The bearing (off the axis) of the pane's nearest point inside the cone: where the echo came from."""
    (ax, ay), (bx, by) = pane
    t = np.linspace(0.0, 1.0, 4001)
    px, py = ax + t * (bx - ax), ay + t * (by - ay)
    bearing = (np.arctan2(py - echo.y, px - echo.x) - echo.yaw + math.pi) % (2 * math.pi) - math.pi
    distance = np.where(np.abs(bearing) <= HALF_FOV, np.hypot(px - echo.x, py - echo.y), np.inf)
    return float(bearing[int(np.argmin(distance))])


def test_two_looks_at_an_oblique_pane_place_the_echo_where_the_pane_touches_the_arc() -> None:
    """The pane's normal lies inside both cones: the newer echo came from near the tangent's bearing, and
    the arc's other end (12 cm in front of the pane here) is left out."""
    pane = ((3.43, -0.60), (2.26, 2.16))  # its normal 0.4 rad from +x, the sonar looking along 0.3 rad
    older, newer = _echo(pane, 1.0, -0.3, 0.3), _echo(pane, 1.0, 0.3, 0.3)  # 0.6 m apart, across the cone
    mask = placed_by(newer, older, BEARINGS, CELL_HALF_ANGLE)
    assert mask is not None
    touching = _touching_bearing(newer, pane)
    assert np.abs(BEARINGS[mask] - touching).min() < 0.02, "the pane's own bearing is kept"
    assert np.abs(BEARINGS[mask] - touching).max() < 0.1, "the far side of the arc is left out"


def test_driving_straight_at_a_flat_pane_keeps_the_whole_arc() -> None:
    pane = ((3.0, -2.0), (3.0, 2.0))
    older, newer = _echo(pane, 1.0, 0.0, 0.0), _echo(pane, 1.4, 0.0, 0.0)
    mask = placed_by(newer, older, BEARINGS, CELL_HALF_ANGLE)
    assert mask is not None and mask.mean() > 0.9, "moving straight at a pane says nothing of where across it"


def test_a_pane_crossing_the_cones_edge_is_placed_on_that_edge() -> None:
    """Beside the robot at a slant, the pane's nearest point in the cone is where it crosses the cone's edge,
    not where a line would touch the arc; the arc's middle lies on open floor in front of it."""
    pane = ((1.8, -0.5), (4.5, 1.77))  # 40 degrees to +x; the robot drives along +x, the sonar at 0.3 rad
    older, newer = _echo(pane, 0.7, 0.0, 0.3), _echo(pane, 1.0, 0.0, 0.3)
    assert abs(_touching_bearing(newer, pane) + HALF_FOV) < 0.01, "the echo comes from the right edge"
    mask = placed_by(newer, older, BEARINGS, CELL_HALF_ANGLE)
    assert mask is not None
    assert mask[BEARINGS < -HALF_FOV + 0.03].all(), "the right edge is kept"
    assert not mask[BEARINGS > 0.0].any(), "the arc's left half is open floor"


def test_echoes_that_cannot_share_a_surface_do_not_pair() -> None:
    near = Echo(1.0, 1.89, 0.0, 1.0, HALF_FOV)
    assert placed_by(near, Echo(0.5, 1.5, 0.0, 2.5, HALF_FOV), BEARINGS, CELL_HALF_ANGLE) is None, (
        "ranges 1.5 m apart from sensors 0.63 m apart, facing the same way: two surfaces"
    )
    assert placed_by(near, Echo(1.0, 1.95, 0.0, 1.0, HALF_FOV), BEARINGS, CELL_HALF_ANGLE) is None, (
        "6 cm apart: the ranges' noise allows the whole cone"
    )
    assert placed_by(near, Echo(3.0, 1.89, 0.0, 1.0, HALF_FOV), BEARINGS, CELL_HALF_ANGLE) is None, (
        "2 m apart: too far to be the same surface's echoes"
    )


def test_an_echo_no_other_can_place_waits_with_part_of_its_evidence() -> None:
    pairing = EchoPairing()
    first = Echo(1.0, 0.0, 0.3, 2.0, HALF_FOV)
    assert pairing.where(first, BEARINGS, CELL_HALF_ANGLE) is None
    pairing.keep(first, resolved=False)
    second = Echo(1.3, 0.0, 0.3, 1.8, HALF_FOV)
    assert pairing.unresolved_near(second) == [first]
    pairing.resolved(first)
    assert pairing.unresolved_near(second) == []
    pairing.clear()
    assert pairing.where(second, BEARINGS, CELL_HALF_ANGLE) is None


def _false_marks(memory: GlassMemory, pane: tuple[tuple[float, float], tuple[float, float]]) -> int:
    iy, ix = np.nonzero(memory.sonar_layer == 254)
    xy = memory.frame.cells_to_world(np.stack([ix, iy], axis=1))
    a, b = np.asarray(pane[0]), np.asarray(pane[1])
    t = np.clip(((xy - a) @ (b - a)) / float((b - a) @ (b - a)), 0.0, 1.0)
    return int(np.count_nonzero(np.hypot(*(xy - (a + t[:, None] * (b - a))).T) > 0.1))


def test_driving_past_an_oblique_pane_marks_the_pane_and_not_the_floor_in_front_of_it() -> None:
    """A robot drives along +x, 10 cm every look, its heading swaying round 0.3 rad as it follows its path,
    past a pane at 40 degrees: each echo comes from the cone's right edge, and the middle of its arc lies on
    the floor in front of the pane. The pairing leaves no more than a cell there, and the pane is marked
    all the same. (Driving dead straight at one heading, an edge crossing and a line touching the arc give
    the same ranges, and the pairing keeps both; only the change of heading tells them apart.)"""
    pane = ((1.8, -0.5), (4.5, 1.77))
    frame = GridFrame(0.05, (0.0, -1.0, 0.0), 120, 90)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0)
    for i, x in enumerate(np.arange(0.0, 1.6, 0.1)):
        echo = _echo(pane, float(x), 0.0, 0.3 + 0.15 * math.sin(0.9 * i))
        memory.add_reading((echo.x, echo.y, echo.yaw), echo.range_m, 2 * HALF_FOV, 0.02, 3.0)
    assert _false_marks(memory, pane) <= 1
    iy, ix = np.nonzero(memory.sonar_layer == 254)
    assert len(ix) - _false_marks(memory, pane) >= 8, "the pane itself is marked"


def test_glass_heard_close_ahead_is_marked_the_first_time_whatever_came_before() -> None:
    """One near echo, no earlier echo to place it: its arc is marked at once (glass heard close ahead must
    stop the robot), though with only part of its evidence until another echo says where it came from."""
    frame = GridFrame(0.05, (0.0, 0.0, 0.0), 80, 60)
    memory = GlassMemory(frame, CostmapParams(), suspicion_radius_m=0.0)
    memory.add_reading((0.5, 1.5, 0.0), 0.8, 2 * HALF_FOV, 0.02, 3.0)
    ahead = frame.world_to_cells(np.array([[1.3, 1.5]]))[0]
    assert memory.sonar_layer[ahead[1], ahead[0]] == 254
