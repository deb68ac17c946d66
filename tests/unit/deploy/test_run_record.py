"""The observer's record of one run: what the demo's picture and report take from it."""

from __future__ import annotations

import pytest

from deploy.observer import RunRecord


def _driven(*points: tuple[float, float]) -> list[tuple[float, float, float, float]]:
    return [(0.05 * i, x, y, 0.0) for i, (x, y) in enumerate(points)]


def test_the_pictures_track_starts_where_the_robot_was_put_down() -> None:
    record = RunRecord(driven=_driven((0.0, 0.0), (0.0, 0.0), (2.0, 1.0), (2.02, 1.0), (2.04, 1.01)))
    assert record.driven_since_placed() == [(2.0, 1.0), (2.02, 1.0), (2.04, 1.01)]


def test_a_track_never_put_down_is_kept_whole_even_with_lost_samples() -> None:
    # 0.2 m between samples: eight lost samples at full speed, still a drive
    record = RunRecord(driven=_driven((0.0, 0.0), (0.025, 0.0), (0.225, 0.0), (0.25, 0.0)))
    assert record.driven_since_placed() == [(0.0, 0.0), (0.025, 0.0), (0.225, 0.0), (0.25, 0.0)]
    assert record.driven_length_m() == pytest.approx(0.25)
    assert RunRecord().driven_since_placed() == []


def test_the_time_to_dock_is_split_by_the_docking_state_it_was_spent_in() -> None:
    record = RunRecord(
        trigger_s=10.0,
        charging_s=30.0,
        phases=[
            (4.0, "IDLE"),
            (10.5, "NAV_TO_STAGING_POSE"),
            (20.0, "INITIAL_PERCEPTION"),
            (21.0, "CONTROLLING"),
            (25.0, "RETRY"),
            (26.0, "CONTROLLING"),
            (31.0, "IDLE"),
        ],
    )
    phases = record.phase_durations()
    assert phases == {
        "TRIGGER": 0.5,
        "NAV_TO_STAGING_POSE": 9.5,
        "INITIAL_PERCEPTION": 1.0,
        "CONTROLLING": 8.0,
        "RETRY": 1.0,
    }
    assert sum(phases.values()) == 20.0


def test_a_run_that_never_charged_has_no_phase_split() -> None:
    assert RunRecord(trigger_s=10.0, phases=[(11.0, "NAV_TO_STAGING_POSE")]).phase_durations() == {}


def test_a_state_the_trigger_found_under_way_counts_from_the_trigger() -> None:
    record = RunRecord(
        trigger_s=10.0, charging_s=14.0, phases=[(9.0, "CONTROLLING"), (12.0, "WAIT_FOR_CHARGE")]
    )
    assert record.phase_durations() == {"CONTROLLING": 2.0, "WAIT_FOR_CHARGE": 2.0}


def test_the_distance_driven_is_split_by_the_docking_state_it_was_driven_in() -> None:
    record = RunRecord(
        trigger_s=10.0,
        charging_s=14.0,
        phases=[(9.0, "IDLE"), (10.5, "NAV_TO_STAGING_POSE"), (12.0, "CONTROLLING")],
        driven=[(10.0 + 0.5 * i, 0.1 * i, 0.0, 0.0) for i in range(9)],  # 0.2 m/s from the trigger on
    )
    lengths = record.phase_lengths_m()
    assert lengths["TRIGGER"] == pytest.approx(0.1)  # 10.0-10.5
    assert lengths["NAV_TO_STAGING_POSE"] == pytest.approx(0.3)  # 10.5-12.0
    assert lengths["CONTROLLING"] == pytest.approx(0.4)  # 12.0-14.0
    assert RunRecord(trigger_s=10.0, phases=[(11.0, "NAV_TO_STAGING_POSE")]).phase_lengths_m() == {}
