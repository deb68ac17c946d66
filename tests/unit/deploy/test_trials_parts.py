"""Trials: reproducible collision-free starts, the stack they run, and the summary arithmetic."""

from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path

import pytest

from deploy.commands.trials import collision_lines
from deploy.trials import (
    START_CLEARANCE_M,
    TrialOptions,
    TrialResult,
    combine,
    random_starts,
    reachable_starts,
    summarise,
    summarise_results,
    trials_stack,
)
from deploy.trials.merge import _trial
from deploy.trials.starts import beacon_starts, distance_to_segment
from services.docking.ir_run import within_beacon_reach
from shared.world import load_world

WORLDS = sorted((Path(__file__).resolve().parents[3] / "deploy" / "worlds").glob("*.yaml"))


@pytest.mark.parametrize("path", WORLDS, ids=lambda p: p.stem)
def test_starts_are_reproducible_clear_and_away_from_the_dock(path: Path) -> None:
    world = load_world(path)
    starts = random_starts(world, 25, seed=3)
    assert starts == random_starts(world, 25, seed=3)
    assert starts != random_starts(world, 25, seed=4)
    segments = world.opaque_segments() + list(world.glass)
    for pose in starts:
        assert world.contains(pose.x, pose.y)
        assert min(distance_to_segment((pose.x, pose.y), s) for s in segments) >= START_CLEARANCE_M
        assert math.dist((pose.x, pose.y), world.docks[0].pose[:2]) >= 1.2


@pytest.mark.parametrize("path", WORLDS, ids=lambda p: p.stem)
def test_beacon_starts_are_clear_and_within_the_infrared_beacons_reach(path: Path) -> None:
    world = load_world(path)
    starts = beacon_starts(world, 20, seed=5)
    assert starts == beacon_starts(world, 20, seed=5)
    segments = world.opaque_segments() + list(world.glass)
    for pose in starts:
        assert min(distance_to_segment((pose.x, pose.y), s) for s in segments) >= START_CLEARANCE_M
        assert within_beacon_reach(pose, world.docks[0].pose2d)


def testdistance_to_segment() -> None:
    assert distance_to_segment((0.0, 1.0), ((-1.0, 0.0), (1.0, 0.0))) == pytest.approx(1.0)
    assert distance_to_segment((3.0, 0.0), ((-1.0, 0.0), (1.0, 0.0))) == pytest.approx(2.0)


def test_stack_gives_each_robot_its_own_services_and_one_simulator() -> None:
    options = TrialOptions(world=WORLDS[0], workers=2)
    stack = trials_stack(options, "tcp/127.0.0.1:7999", ["r0", "r1"])
    assert {"router", "map", "simulator"} <= set(stack.services)
    for robot in ("r0", "r1"):
        for service in ("battery", "pose", "planner", "perception", "docking"):
            spec = stack.services[f"{service}_{robot}"]
            assert spec.namespace == robot
            assert spec.healthcheck is not None and spec.healthcheck.liveliness == service
    assert 'robots=["r0", "r1"]' in stack.services["simulator"].command
    assert "detection.source=aruco" in stack.services["simulator"].command
    synthetic = trials_stack(
        TrialOptions(world=WORLDS[0], workers=2, detector="synthetic"), "tcp/127.0.0.1:7999", ["r0"]
    )
    assert "perception_r0" not in synthetic.services
    assert "detection.source=synthetic" in synthetic.services["simulator"].command


def test_a_composed_campaign_runs_each_robots_services_in_one_container() -> None:
    options = TrialOptions(world=WORLDS[0], workers=2, compose="all")
    stack = trials_stack(options, "tcp/127.0.0.1:7999", ["r0", "r1"])
    assert set(stack.services) == {"router", "map", "simulator", "robot_r0", "robot_r1"}
    group = stack.services["robot_r0"]
    assert group.namespace == "r0"
    assert group.healthcheck is not None and group.healthcheck.liveliness == "docking"
    assert group.depends_on["map"].condition == "service_completed_successfully"
    assert group.command[:2] == ["zendock", "container"]
    assert group.members == ("battery", "pose", "planner", "perception", "docking")
    light = trials_stack(
        TrialOptions(world=WORLDS[0], compose="light"), "tcp/127.0.0.1:7999", ["r0"]
    ).services
    assert {"robot_r0", "planner_r0", "perception_r0", "docking_r0"} <= set(light)
    assert "battery_r0" not in light and light["robot_r0"].members == ("battery", "pose")
    assert light["robot_r0"].healthcheck is not None and light["robot_r0"].healthcheck.liveliness == "pose"


def _result(i: int, docked: bool, time_s: float, lateral_m: float, collisions: int = 0) -> TrialResult:
    return TrialResult(
        i, "r0", (0.0, 0.0, 0.0), docked, docked, time_s, lateral_m, 0.01, collisions, 1.0, 4.0
    )


def test_summary_counts_only_docked_runs_in_the_medians() -> None:
    too_fast = _result(3, False, 12.0, 0.002)
    too_fast.charging, too_fast.too_fast, too_fast.arrival_speed_mps = True, True, 0.3
    results = [
        _result(0, True, 10.0, 0.001),
        _result(1, True, 20.0, 0.003),
        _result(2, False, math.nan, math.nan, 1),  # never mated: no arrival speed
        too_fast,  # charged, but met the plate too fast: a failure whose speed still counts
    ]
    results[0].arrival_speed_mps, results[1].arrival_speed_mps = 0.08, 0.12
    results[0].glass_slowed_s, results[1].glass_slowed_s = 1.0, 3.0
    too_fast.glass_slowed_s = 9.0  # not docked: not in the median
    summary = summarise(
        results, wall_s=5.0, options=TrialOptions(world=WORLDS[0]), world=load_world(WORLDS[0])
    )
    assert (summary.n, summary.successes, summary.collisions) == (4, 2, 1)
    assert summary.success_rate == pytest.approx(2 / 4)
    assert summary.median_dock_time_s == pytest.approx(15.0)
    assert summary.p95_lateral_error_m == pytest.approx(0.003)
    assert set(summary.headline()) == {
        "n",
        "successes",
        "success_rate",
        "median_dock_time_s",
        "median_lower_bound_s",
        "median_time_ratio",
        "median_lateral_error_m",
        "p95_lateral_error_m",
        "median_yaw_error_rad",
        "median_arrival_speed_mps",
        "max_arrival_speed_mps",
        "collisions",
        "wall_s",
        "sim_s",
        "achieved_rtf",
        "median_false_glass_cells",
        "p95_false_glass_cells",
        "median_glass_coverage",
        "heard_panes_found",
        "near_glass_trials",
        "p05_glass_clearance_m",
    }
    assert summary.median_time_ratio == pytest.approx(3.75)  # 10/4 and 20/4
    assert (summary.median_arrival_speed_mps, summary.max_arrival_speed_mps) == pytest.approx((0.12, 0.3))
    assert summary.median_glass_slowed_s == pytest.approx(2.0)


def test_time_ratio_is_each_trials_own_ratio_and_skips_missing_bounds() -> None:
    fast_short = _result(0, True, 6.0, 0.001)
    fast_short.lower_bound_s = 5.0
    slow_long = _result(1, True, 30.0, 0.001)
    slow_long.lower_bound_s = 10.0
    unbounded = _result(2, True, 99.0, 0.001)
    unbounded.lower_bound_s = math.nan
    summary = summarise_results([fast_short, slow_long, unbounded], 1.0, "graceful", "w")
    assert summary.median_time_ratio == pytest.approx((1.2 + 3.0) / 2)
    assert summary.median_lower_bound_s == pytest.approx(7.5)


def test_a_campaign_combines_every_trial_not_the_medians() -> None:
    a = [_result(0, True, 10.0, 0.001), _result(1, True, 11.0, 0.001), _result(2, True, 12.0, 0.001)]
    b = [_result(0, True, 40.0, 0.004), _result(1, False, math.nan, math.nan, 2)]
    sa = summarise_results(a, 3.0, "graceful", "a")
    sb = summarise_results(b, 4.0, "graceful", "b")
    sa.peak_rss_mb, sb.peak_rss_mb = {"planner_r0": 70.0}, {"planner_r0": 75.0, "simulator": 60.0}
    sa.sim_s, sb.sim_s = 10.0, 30.0
    sa.cpu_s_per_sim_s, sb.cpu_s_per_sim_s = {"simulator": 0.1}, {"simulator": 0.3, "planner_r0": 0.2}
    sa.chaos = {"kills": 2, "recovered": 2, "killed": ["pose_r0", "docking_r0"], "recovery_s": [1.0, 3.0]}
    both = combine([(sa, a), (sb, b)], "graceful")
    assert (both.n, both.successes, both.collisions) == (5, 4, 2)
    assert both.median_dock_time_s == pytest.approx(11.5)  # median of 10, 11, 12, 40
    assert both.wall_s == pytest.approx(7.0) and both.world == "a, b"
    assert both.peak_rss_mb == {"planner_r0": 75.0, "simulator": 60.0}
    # CPU per sim second over the whole campaign: each world's weighted by its sim seconds
    assert both.cpu_s_per_sim_s == pytest.approx({"simulator": 0.25, "planner_r0": 0.2})
    assert both.chaos["kills"] == 2 and both.chaos["median_recovery_s"] == pytest.approx(2.0)
    assert both.chaos["p95_recovery_s"] == pytest.approx(3.0) and both.chaos[
        "max_recovery_s"
    ] == pytest.approx(3.0)


def test_starts_in_a_closed_pocket_are_skipped_and_the_rest_keep_their_order() -> None:
    path = next(w for w in WORLDS if w.stem == "corridor")
    world = load_world(path)
    starts = reachable_starts(path, world, 20, seed=1)
    pockets = [s for s in starts if 1.8 < s.x < 5.6 and (s.y < 1.0 or s.y > 2.0)]  # walled off from the rooms
    assert len(starts) == 20 and not pockets
    candidates = random_starts(world, 50, seed=1)
    assert any(1.8 < c.x < 5.6 and (c.y < 1.0 or c.y > 2.0) for c in candidates)  # the seed does make some
    assert starts == [c for c in candidates if c in starts]  # same order as the seed made them


def test_chaos_kills_robot_services_or_a_composed_robots_one_process() -> None:
    from deploy.trials.chaos import ChaosMonkey, chaos_victims

    alone = [
        ("router", []),
        ("simulator", []),
        ("map", []),
        ("battery_r0", []),
        ("planner_r0", []),
        ("perception_r0", []),
        ("docking_r1", []),
    ]
    assert chaos_victims(alone, ["r0", "r1"], ChaosMonkey.VICTIMS) == [
        "battery_r0",
        "planner_r0",
        "docking_r1",
    ]
    composed = [
        ("simulator", []),
        ("robot_r0", ["battery", "pose", "planner", "docking"]),
        ("perception_r0", []),
        ("robot_r1", ["battery", "pose"]),
        ("planner_r1", []),
    ]
    assert chaos_victims(composed, ["r0", "r1"], ChaosMonkey.VICTIMS) == [
        "robot_r0",
        "robot_r1",
        "planner_r1",
    ]


def test_the_summary_gives_each_docking_states_median_with_a_missing_state_as_zero() -> None:
    from deploy.trials.summary import median_phases

    trials = [
        {"NAV_TO_STAGING_POSE": 8.0, "CONTROLLING": 3.0},
        {"NAV_TO_STAGING_POSE": 10.0, "CONTROLLING": 5.0, "RETRY": 2.0},
        {"NAV_TO_STAGING_POSE": 12.0, "CONTROLLING": 4.0},
    ]
    assert median_phases(trials) == {"NAV_TO_STAGING_POSE": 10.0, "CONTROLLING": 4.0, "RETRY": 0.0}


def test_a_trial_that_touched_something_says_what_where_and_how_to_start_it_again() -> None:
    """A campaign's collisions were a count: finding what a trial had hit meant reading the simulator's log
    of a run directory. Each trial now keeps what it touched and where, through a merge too, and the
    command names it with the line that starts it again from the same pose."""
    clean = _result(0, True, 10.0, 0.001)
    hit = _result(1, True, 30.0, 0.002, collisions=2)
    hit.start = (1.3687, 0.7163, -0.1117)
    hit.collided = [{"kind": "glass", "x": 5.9, "y": 5.74}, {"kind": "wall", "x": 6.43, "y": 5.5}]
    options = TrialOptions(
        world=Path("/rooms/generated-glass-184-1.yaml"), seed=84100, detector="synthetic", rtf="5"
    )
    assert collision_lines([clean, hit], options) == [
        "collision: generated-glass-184-1 trial 1 from (1.37, 0.72, -0.11) touched glass at (5.90, 5.74), "
        "wall at (6.43, 5.50); again: zendock trials --world /rooms/generated-glass-184-1.yaml --n 2 "
        "--seed 84100 --controller graceful --detector synthetic --rtf 5"
    ]
    lost = _result(2, False, math.nan, math.nan)
    lost.start = (2.0, 3.0, 0.5)
    fast = _result(3, False, math.nan, math.nan)
    fast.start, fast.too_fast = (1.0, 1.0, 0.0), True
    again = (
        "zendock trials --world /rooms/generated-glass-184-1.yaml --n {} --seed 84100 --controller graceful"
    )
    assert collision_lines([lost, fast], options) == [
        "not docked: generated-glass-184-1 trial 2 from (2.00, 3.00, 0.50) did not charge within the trial's "
        f"limit; again: {again.format(3)} --detector synthetic --rtf 5",
        "not docked: generated-glass-184-1 trial 3 from (1.00, 1.00, 0.00) met the plate faster than the "
        f"contact speed limit; again: {again.format(4)} --detector synthetic --rtf 5",
    ]
    assert _trial(asdict(hit)).collided == hit.collided
    assert _trial({k: v for k, v in asdict(clean).items() if k != "collided"}).collided == []
