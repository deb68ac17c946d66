import math

from services.docking.approach import dock_frame_error, line_approach
from services.docking.bench import (
    CONTROLLERS,
    SEED_ROOM_DOCK,
    compare_controllers,
    format_comparison,
    seed_goals_ahead,
    staging_grid,
)
from shared.geometry import Pose2D


def test_staging_grid_is_behind_the_dock() -> None:
    starts = staging_grid(SEED_ROOM_DOCK)
    assert len(starts) == 27
    errors = [dock_frame_error(s, SEED_ROOM_DOCK) for s in starts]
    assert {round(-e.along_m, 6) for e in errors} == {0.5, 0.75, 1.0}
    assert {round(e.lateral_m, 6) for e in errors} == {-0.15, 0.0, 0.15}


def test_seed_gets_the_waypoints_ahead_of_its_start() -> None:
    approach = line_approach(SEED_ROOM_DOCK)
    far = staging_grid(SEED_ROOM_DOCK, back_m=(1.0,), lateral_m=(0.0,), yaw_rad=(0.0,))[0]
    near = staging_grid(SEED_ROOM_DOCK, back_m=(0.5,), lateral_m=(0.0,), yaw_rad=(0.0,))[0]
    assert seed_goals_ahead(far, SEED_ROOM_DOCK) == [approach.front_waypoint, approach.dock]
    assert seed_goals_ahead(near, SEED_ROOM_DOCK) == [approach.dock]
    assert seed_goals_ahead(Pose2D(-1.0, 2.5, -math.pi / 2), SEED_ROOM_DOCK) == list(approach.goals)


def test_tuned_controller_beats_seed_and_nav2_defaults() -> None:
    starts = staging_grid(SEED_ROOM_DOCK, back_m=(0.7, 1.0), lateral_m=(-0.1, 0.1), yaw_rad=(0.2,))
    report = compare_controllers(starts=starts, include_seed_full_run=False)
    rows = report["controllers"]
    assert set(rows) == set(CONTROLLERS)
    seed, nav2, tuned = rows["seed"], rows["graceful_nav2"], rows["graceful_zendock"]
    assert tuned["mated"] == tuned["runs"] == len(starts)
    assert tuned["median_time_s"] < 0.5 * seed["median_time_s"]
    assert tuned["median_time_s"] < nav2["median_time_s"]
    assert tuned["median_lateral_error_mm"] < 5.0
    assert tuned["median_yaw_error_deg"] < min(
        0.5, seed["median_yaw_error_deg"], nav2["median_yaw_error_deg"]
    )
    table = format_comparison(report)
    for name in CONTROLLERS:
        assert name in table


def test_report_includes_the_seed_full_run() -> None:
    start = staging_grid(SEED_ROOM_DOCK, back_m=(0.7,), lateral_m=(0.0,), yaw_rad=(0.0,))
    report = compare_controllers(starts=start, controllers=["graceful_zendock"])
    full = report["seed_full_run"]
    assert full["contact"] and full["time_s"] > 30.0
    assert "seed from its staging goal" in format_comparison(report)
