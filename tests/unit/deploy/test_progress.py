"""The lines the long commands print while they run (deploy.progress, the fleet's live table)."""

import io
import math

from rich.console import Console

from deploy.commands.fleet import live_table
from deploy.fleet.monitor import RobotTally
from deploy.progress import Throttle, demo_line, dock_line, eta_text, progress_period_s, trials_line


def test_the_demo_shows_the_battery_before_the_trigger_and_the_approach_after() -> None:
    before = demo_line(sim_s=12.34, battery=0.2581, trigger_s=None, docking_state="", distance_m=None)
    assert before == "waiting for the low-battery trigger (25 %): battery 25.8 %, sim 12.3 s"
    after = demo_line(
        sim_s=40.0, battery=0.249, trigger_s=22.0, docking_state="NAV_TO_STAGING", distance_m=2.416
    )
    assert after == "docking: NAV_TO_STAGING, 2.42 m to dock, sim 40.0 s (trigger +18.0 s)"
    unknown = demo_line(sim_s=23.0, battery=None, trigger_s=22.0, docking_state="", distance_m=math.nan)
    assert "starting, distance to dock unknown" in unknown


def test_a_dock_line_keeps_its_columns_and_adds_the_distance_when_known() -> None:
    assert (
        dock_line(docking_time_s=12.34, state="CONTROLLING", retries=0, distance_m=None)
        == "   12.3 s  CONTROLLING"
    )
    assert (
        dock_line(docking_time_s=3.0, state="CONTROLLING", retries=1, distance_m=0.4567)
        == "    3.0 s  CONTROLLING  (retry 1)    0.46 m to the dock"
    )


def test_the_campaign_line_counts_successes_and_estimates_the_rest() -> None:
    assert eta_text(0, 50, 10.0) == "?"
    assert eta_text(10, 50, 100.0) == "6:40"
    assert (
        trials_line(world="seed_room", done=10, total=50, successes=9, elapsed_s=100.0)
        == "trials seed_room: 10/50, 9 docked, ETA 6:40"
    )
    assert trials_line(world="seed_room", done=50, total=50, successes=50, elapsed_s=500.4).endswith(
        "done in 500 s"
    )


def test_a_throttle_lets_one_call_through_per_period() -> None:
    throttle = Throttle(2.0)
    assert [throttle.due(t) for t in (0.0, 1.0, 2.0, 3.9, 4.1)] == [True, False, True, False, True]
    assert progress_period_s(True) < progress_period_s(False)


def test_the_fleet_live_table_lists_each_robot_charge_state_and_dockings() -> None:
    robots = [
        RobotTally("r1", battery=0.634, state="PATROLLING", dockings=2, distance_m=41.2),
        RobotTally("r2", battery=math.nan, charging=True),
    ]
    out = io.StringIO()
    Console(file=out, width=100, color_system=None).print(live_table(125.0, 600.0, robots))
    text = out.getvalue()
    assert "fleet: 125 s of 600 s simulated" in text
    assert "r1" in text and "63 %" in text and "PATROLLING" in text and "41 m" in text
    assert "? +" in text


def test_trials_without_a_terminal_print_a_count_line_on_stderr_only(capsys) -> None:  # type: ignore[no-untyped-def]
    from pathlib import Path
    from types import SimpleNamespace

    from deploy.commands.trials import _run_world
    from deploy.trials.records import Shard

    options = SimpleNamespace(world=Path("seed_room.yaml"), n=12, shard=Shard.parse("1/1"))

    def run_trials(options, log, progress):  # type: ignore[no-untyped-def]
        log("12 trials in seed_room")
        for i in range(12):
            progress(SimpleNamespace(index=i, docked=i != 3, dock_time_s=20.0))
        return "summary", [], Path("run")

    assert _run_world(Console(file=io.StringIO()), options, run_trials) == ("summary", [], Path("run"))
    out, err = capsys.readouterr()
    lines = err.splitlines()
    assert out == "" and [line.split(",")[0] for line in lines] == [
        "trials seed_room: 1/12",
        "trials seed_room: 10/12",
        "trials seed_room: 12/12",
    ]
    assert (
        "9 docked" in lines[1]
        and "ETA" in lines[1]
        and lines[2].startswith("trials seed_room: 12/12, 11 docked, done")
    )
