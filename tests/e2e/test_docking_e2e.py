"""Whole-system docking runs: the default stack through the launcher, judged on the simulator's truth,
with each service its own process and with the robot's services composed into one (``--compose``).

Each run is what ``zendock demo`` does: stack up on a free port, battery set just above the low
threshold, then the trigger, the navigation, the approach and CHARGING, all across real processes.
"""

from __future__ import annotations

from pathlib import Path

import psutil
import pytest

from deploy.demo import DemoOptions, run_demo

WORLDS = sorted((Path(__file__).resolve().parents[2] / "deploy" / "worlds").glob("*.yaml"))
pytestmark = pytest.mark.e2e


def _no_stack_left(run_dir: Path) -> None:
    leftovers = [p.info for p in psutil.process_iter(["pid", "cmdline"])
                 if any(str(run_dir) in part for part in (p.info["cmdline"] or []))]
    assert not leftovers, f"processes left behind: {leftovers}"


def _assert_docked(report, run_dir: Path) -> None:  # type: ignore[no-untyped-def]
    logs = {p.name: p.read_text()[-1500:] for p in run_dir.glob("*/*.log")} if not report.docked else {}
    assert report.docked and report.charging, f"did not dock: {report.as_dict()}\n{logs}"
    assert report.collisions == 0, report.as_dict()
    assert report.final_lateral_error_m < 0.04 and report.final_yaw_error_rad < 0.1, report.as_dict()


COMPOSE = pytest.mark.parametrize("compose", [False, True], ids=["process-per-service", "composed"])


@COMPOSE
def test_seed_controller_docks_in_seed_room(tmp_path: Path, compose: bool) -> None:
    report = run_demo(DemoOptions(world=WORLDS[0].parent / "seed_room.yaml", controller="seed", rtf="5",
                                  runs_dir=tmp_path, timeout_sim_s=400.0, compose=compose), log=lambda _t: None)
    _assert_docked(report, tmp_path)
    assert (Path(report.run_dir) / "trajectory.png").stat().st_size > 10_000
    _no_stack_left(tmp_path)


@COMPOSE
@pytest.mark.parametrize("world", WORLDS, ids=lambda p: p.stem)
def test_graceful_controller_docks_in_every_shipped_world(world: Path, tmp_path: Path, compose: bool) -> None:
    report = run_demo(DemoOptions(world=world, controller="graceful", rtf="4", runs_dir=tmp_path,
                                  localisation_error=(0.03, -0.02, 0.02), compose=compose), log=lambda _t: None)
    _assert_docked(report, tmp_path)
    _no_stack_left(tmp_path)
