"""How close a trial's footprint came to glass: the gap to each pane on ground truth, and the campaign's
near misses."""

from __future__ import annotations

import math

import pytest

from deploy.trials.glass_clearance import CLEARANCE_CAP_M, NEAR_GLASS_M, closest_glass_pass, pane_points
from deploy.trials.records import TrialResult
from deploy.trials.summary import summarise_results
from shared.world import ROBOT_LENGTH_M, ROBOT_WIDTH_M, World, parse_world

HALF_L, HALF_W = ROBOT_LENGTH_M / 2, ROBOT_WIDTH_M / 2
#: The figure's resolution: pane points 5 mm apart, so a gap reads at most half of that too wide.
TOL = 0.003


def _world(glass: list) -> World:  # type: ignore[type-arg]
    return parse_world(
        {
            "name": "w",
            "bounds": [-5.0, -5.0, 5.0, 5.0],
            "walls": [],
            "glass": glass,
            "boxes": [],
            "docks": [],
            "robot": {"start": [0.0, 0.0, 0.0]},
        }
    )


def test_a_pane_across_the_front_is_as_far_as_the_front_face() -> None:
    world = _world([[[HALF_L + 0.1, -1.0], [HALF_L + 0.1, 1.0]]])  # across the heading, 10 cm ahead
    closest = closest_glass_pass(world, [(0.0, 0.0, 0.0, 0.0)])
    assert closest is not None
    assert closest.clearance_m == pytest.approx(0.1, abs=TOL)
    assert closest.x == pytest.approx(HALF_L + 0.1) and abs(closest.y) <= HALF_W + TOL


def test_the_footprint_turns_with_the_robot() -> None:
    world = _world([[[-1.0, HALF_L + 0.1], [1.0, HALF_L + 0.1]]])  # along x, 10 cm past the front at yaw pi/2
    facing = closest_glass_pass(world, [(0.0, 0.0, 0.0, math.pi / 2)])
    sideways = closest_glass_pass(world, [(0.0, 0.0, 0.0, 0.0)])
    assert facing is not None and sideways is not None
    assert facing.clearance_m == pytest.approx(0.1, abs=TOL)
    assert sideways.clearance_m == pytest.approx(HALF_L - HALF_W + 0.1, abs=TOL)  # the side is nearer


def test_a_pane_end_beside_a_corner_is_measured_to_the_corner() -> None:
    world = _world([[[HALF_L + 0.03, HALF_W + 0.04], [2.0, 2.0]]])  # its end 3 cm ahead, 4 cm aside
    closest = closest_glass_pass(world, [(0.0, 0.0, 0.0, 0.0)])
    assert closest is not None
    assert closest.clearance_m == pytest.approx(0.05, abs=TOL)
    assert (closest.x, closest.y) == pytest.approx((HALF_L + 0.03, HALF_W + 0.04), abs=TOL)


def test_a_pane_through_the_footprint_is_no_gap() -> None:
    world = _world([[[-1.0, 0.05], [1.0, 0.05]]])  # runs through the robot, ends outside it
    closest = closest_glass_pass(world, [(0.0, 0.0, 0.0, 0.3)])
    assert closest is not None and closest.clearance_m == 0.0


def test_the_closest_sample_of_the_track_counts() -> None:
    world = _world([[[1.0, -1.0], [1.0, 1.0]]])
    track = [(t, x, 0.0, 0.0) for t, x in ((0.0, 0.0), (0.05, 0.5), (0.1, 0.7), (0.15, 0.4))]
    closest = closest_glass_pass(world, track)
    assert closest is not None
    assert closest.clearance_m == pytest.approx(1.0 - 0.7 - HALF_L, abs=TOL)


def test_glass_out_of_reach_reads_the_cap_and_no_glass_reads_nothing() -> None:
    far = _world([[[4.0, -1.0], [4.0, 1.0]]])
    closest = closest_glass_pass(far, [(0.0, 0.0, 0.0, 0.0)])
    assert closest is not None and closest.clearance_m == CLEARANCE_CAP_M and math.isnan(closest.x)
    assert closest_glass_pass(_world([]), [(0.0, 0.0, 0.0, 0.0)]) is None
    assert closest_glass_pass(far, []) is None


def test_pane_points_cover_each_pane_end_to_end() -> None:
    points = pane_points(_world([[[0.0, 0.0], [1.0, 0.0]]]), spacing_m=0.1)
    assert len(points) == 11
    assert points[0].tolist() == [0.0, 0.0] and points[-1].tolist() == [1.0, 0.0]


def _trial(i: int, clearance_m: float) -> TrialResult:
    result = TrialResult(i, "r0", (0.0, 0.0, 0.0), True, True, 10.0, 0.001, 0.01, 0, 1.0, 8.0)
    result.glass_clearance_m = clearance_m
    return result


def test_the_summary_counts_near_misses_and_the_closest_passes() -> None:
    clearances = [0.0, 0.02, NEAR_GLASS_M, 0.2, 0.3, 0.5, CLEARANCE_CAP_M]
    summary = summarise_results(
        [_trial(i, c) for i, c in enumerate(clearances)] + [_trial(9, math.nan)], 1.0, "graceful", "w"
    )
    assert summary.near_glass_trials == 2  # a touch and a 2 cm pass; 5 cm is not nearer than 5 cm
    assert 0.0 <= summary.p05_glass_clearance_m <= 0.02
    no_glass = summarise_results([_trial(0, math.nan)], 1.0, "graceful", "w")
    assert no_glass.near_glass_trials == 0 and math.isnan(no_glass.p05_glass_clearance_m)
