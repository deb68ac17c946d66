"""A docking's time over its lower bound, split into the reaction, navigation, glass, detours and the approach."""

from __future__ import annotations

import math

import pytest

from deploy.trials.time_over_bound import (
    BOUND_MAX_ANGULAR_RADPS,
    BOUND_MAX_LINEAR_MPS,
    GlassSlowing,
    LowerBound,
    time_over_bound,
)

PHASES = {"TRIGGER": 0.2, "NAV_TO_STAGING_POSE": 8.0, "INITIAL_PERCEPTION": 0.1, "CONTROLLING": 2.9}
LENGTHS = {"TRIGGER": 0.0, "NAV_TO_STAGING_POSE": 3.0, "INITIAL_PERCEPTION": 0.0, "CONTROLLING": 0.45}


def test_the_parts_add_up_to_the_time_over_the_bound() -> None:
    bound = LowerBound(
        seconds=3.2 / BOUND_MAX_LINEAR_MPS + 1.5 / BOUND_MAX_ANGULAR_RADPS, path_length_m=3.2, turn_rad=1.5
    )
    for glass in (None, GlassSlowing(seconds=4.0, metres=0.8)):
        parts = time_over_bound(PHASES, LENGTHS, bound, glass)
        assert sum(parts.values()) == pytest.approx(sum(PHASES.values()) - bound.seconds, abs=1e-3)


def test_each_part_is_what_its_states_took_beyond_full_speed() -> None:
    bound = LowerBound(seconds=8.0, path_length_m=3.2, turn_rad=1.5)
    parts = time_over_bound(PHASES, LENGTHS, bound)
    assert parts["trigger"] == pytest.approx(0.2)  # the bound has no reaction time
    # 3 m at 0.5 m/s is 6 s: 2 s over
    assert parts["navigation"] == pytest.approx(8.0 - 3.0 / BOUND_MAX_LINEAR_MPS)
    # 3.45 m driven against the bound's 3.2 m
    assert parts["detour"] == pytest.approx(0.25 / BOUND_MAX_LINEAR_MPS)
    # the bound turns 1.5 rad in place at 1.5 rad/s; the robot turned while it drove
    assert parts["turns"] == pytest.approx(-1.0)
    assert parts["approach"] == pytest.approx(3.0 - 0.45 / BOUND_MAX_LINEAR_MPS)
    assert parts["other"] == 0.0
    assert parts["glass"] == 0.0  # nothing counted of glass: all of navigation's time stays there


def test_glass_slowing_is_taken_out_of_navigation() -> None:
    bound = LowerBound(seconds=8.0, path_length_m=3.2, turn_rad=1.5)
    without = time_over_bound(PHASES, LENGTHS, bound)
    # 4 s under a glass limit in which the robot drove 0.8 m: 1.6 s of driving at full speed, 2.4 s lost
    parts = time_over_bound(PHASES, LENGTHS, bound, GlassSlowing(seconds=4.0, metres=0.8))
    assert parts["glass"] == pytest.approx(4.0 - 0.8 / BOUND_MAX_LINEAR_MPS)
    assert parts["navigation"] == pytest.approx(without["navigation"] - parts["glass"])
    assert {k: v for k, v in parts.items() if k not in ("glass", "navigation")} == {
        k: v for k, v in without.items() if k not in ("glass", "navigation")
    }


def test_a_glass_count_the_planner_did_not_keep_leaves_navigation_whole() -> None:
    bound = LowerBound(seconds=8.0, path_length_m=3.2, turn_rad=1.5)
    parts = time_over_bound(PHASES, LENGTHS, bound, GlassSlowing(seconds=math.nan, metres=math.nan))
    assert parts == time_over_bound(PHASES, LENGTHS, bound)


def test_a_retry_counts_as_other() -> None:
    phases = {**PHASES, "RETRY": 1.5}
    lengths = {**LENGTHS, "RETRY": 0.25}
    parts = time_over_bound(phases, lengths, LowerBound(seconds=8.0, path_length_m=3.2, turn_rad=1.5))
    assert parts["other"] == pytest.approx(1.5 - 0.25 / BOUND_MAX_LINEAR_MPS)


def test_no_bound_no_parts() -> None:
    assert time_over_bound(PHASES, LENGTHS, LowerBound(math.nan, math.nan, math.nan)) == {}
