"""The ultrasonic cone: the nearest surface anywhere inside it, as a ping that fills the cone hears it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shared.models.raycast import SegmentSet, cast_rays, nearest_in_cone

HALF = 0.25


def brute_force(origin: tuple[float, float], yaw: float, segments: list, samples: int = 20001) -> float:
    """The same answer by sampling every segment densely and keeping the points inside the cone."""
    best = math.inf
    for (ax, ay), (bx, by) in segments:
        t = np.linspace(0.0, 1.0, samples)
        px, py = ax + t * (bx - ax) - origin[0], ay + t * (by - ay) - origin[1]
        bearing = np.abs((np.arctan2(py, px) - yaw + math.pi) % (2 * math.pi) - math.pi)
        inside = bearing <= HALF
        if inside.any():
            best = min(best, float(np.hypot(px, py)[inside].min()))
    return best


def test_a_pane_seen_end_on_between_rays_is_heard() -> None:
    # A pane pointing straight at the sensor, its end 1.5 m out on the axis between seven rays' bearings
    # (0.083 rad apart); a fan of rays slips past it, the cone does not.
    pane = [((1.5, 0.02), (3.0, 0.04))]
    rays = cast_rays((0.0, 0.0), np.linspace(-HALF, HALF, 7), SegmentSet(pane))
    assert np.isinf(rays).all()
    assert nearest_in_cone((0.0, 0.0), 0.0, HALF, SegmentSet(pane)) == pytest.approx(math.hypot(1.5, 0.02))


def test_a_wall_straight_ahead_reads_its_perpendicular_distance() -> None:
    wall = SegmentSet([((2.0, -3.0), (2.0, 3.0))])
    assert nearest_in_cone((0.5, 0.0), 0.0, HALF, wall) == pytest.approx(1.5)


def test_an_oblique_pane_echoes_from_the_cone_edge_nearest_it() -> None:
    # A pane at 45 degrees: its nearest point inside the cone lies on the cone's lower edge.
    pane = SegmentSet([((1.0, -1.0), (3.0, 1.0))])
    edge = -HALF
    # On the edge ray p = r (cos e, sin e): x - y = 2, so r = 2 / (cos e - sin e).
    assert nearest_in_cone((0.0, 0.0), 0.0, HALF, pane) == pytest.approx(
        2.0 / (math.cos(edge) - math.sin(edge))
    )


def test_nothing_behind_or_beside_the_cone() -> None:
    behind = SegmentSet([((-2.0, -1.0), (-2.0, 1.0))])
    beside = SegmentSet([((0.0, 1.0), (3.0, 1.5))])  # entirely above the upper edge
    assert math.isinf(nearest_in_cone((0.0, 0.0), 0.0, HALF, behind))
    assert math.isinf(nearest_in_cone((0.0, 0.0), 0.0, HALF, beside))
    assert math.isinf(nearest_in_cone((0.0, 0.0), 0.0, HALF, SegmentSet([])))


def test_parallel_to_an_edge_and_degenerate_segments() -> None:
    upper = (math.cos(HALF), math.sin(HALF))
    along_edge = SegmentSet([((upper[0], upper[1]), (2 * upper[0], 2 * upper[1]))])
    assert nearest_in_cone((0.0, 0.0), 0.0, HALF, along_edge) == pytest.approx(1.0)
    point = SegmentSet([((1.0, 0.1), (1.0, 0.1))])
    assert nearest_in_cone((0.0, 0.0), 0.0, HALF, point) == pytest.approx(math.hypot(1.0, 0.1))


def test_half_angle_is_checked() -> None:
    with pytest.raises(ValueError, match="half angle"):
        nearest_in_cone((0.0, 0.0), 0.0, math.pi, SegmentSet([((1.0, 0.0), (2.0, 0.0))]))


@pytest.mark.parametrize("seed", range(30))
def test_matches_dense_sampling(seed: int) -> None:
    rng = np.random.default_rng(seed)
    segments = [tuple(map(tuple, rng.uniform(-3.0, 3.0, size=(2, 2)))) for _ in range(4)]
    origin = tuple(rng.uniform(-1.0, 1.0, size=2))
    yaw = float(rng.uniform(-math.pi, math.pi))
    expected = brute_force(origin, yaw, segments)
    got = nearest_in_cone(origin, yaw, HALF, SegmentSet(segments))
    if math.isinf(expected):
        assert math.isinf(got)
    else:
        assert got == pytest.approx(expected, abs=2e-3)
