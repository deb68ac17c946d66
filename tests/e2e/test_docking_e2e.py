"""Whole-system docking runs: the default stack through the launcher, judged on the simulator's truth,
with each service its own process and with the robot's services composed into one (``--compose``).

Each run is what ``zendock demo`` does: stack up on a free port, battery set low, then the trigger, the
navigation, the approach and CHARGING, all across real processes. The graceful controller's
process-per-service runs go through zendock's pytest plugin (``zendock_stack``, ``zendock_robot``:
:mod:`deploy.testing`), as a user's tests would, so CI exercises it, and ``pytest tests/e2e
--zendock-service docking='python my_docking.py'`` runs them against a replacement; the others go
through ``run_demo``.
"""

from __future__ import annotations

from pathlib import Path

import psutil
import pytest

from deploy.demo import DemoOptions, run_demo
from deploy.testing import Robot, ZendockStack, is_charging
from shared import topics

WORLDS = sorted((Path(__file__).resolve().parents[2] / "deploy" / "worlds").glob("*.yaml"))
pytestmark = pytest.mark.e2e


def _no_stack_left(run_dir: Path) -> None:
    leftovers = [
        p.info
        for p in psutil.process_iter(["pid", "cmdline"])
        if any(str(run_dir) in part for part in (p.info["cmdline"] or []))
    ]
    assert not leftovers, f"processes left behind: {leftovers}"


def _assert_docked(report, run_dir: Path) -> None:  # type: ignore[no-untyped-def]
    logs = {p.name: p.read_text()[-1500:] for p in run_dir.glob("*/*.log")} if not report.docked else {}
    assert report.docked and report.charging, f"did not dock: {report.as_dict()}\n{logs}"
    assert report.collisions == 0, report.as_dict()
    assert report.final_lateral_error_m < 0.04 and report.final_yaw_error_rad < 0.1, report.as_dict()


def test_seed_controller_docks_in_seed_room(tmp_path: Path) -> None:
    """The tutorial's own three-step approach (the composed robot docks in the graceful runs below)."""
    report = run_demo(
        DemoOptions(
            world=WORLDS[0].parent / "seed_room.yaml",
            controller="seed",
            rtf="5",
            runs_dir=tmp_path,
            timeout_sim_s=400.0,
        ),
        log=lambda _t: None,
    )
    _assert_docked(report, tmp_path)
    assert (Path(report.run_dir) / "trajectory.png").stat().st_size > 10_000
    _no_stack_left(tmp_path)


#: What the graceful runs share: the controller, the simulator's pace, a localisation that is a little off.
GRACEFUL = {"controller": "graceful", "rtf": 4, "localisation_error": (0.03, -0.02, 0.02)}
#: Below the docking service's low threshold (0.25): the battery crosses it, docking starts.
LOW_BATTERY = 0.2
#: From the low battery to CHARGING, wall seconds (the demo's limit is 300 sim s, 75 s at rtf 4).
DOCK_WITHIN_S = 200.0


@pytest.mark.parametrize(
    "world", [pytest.param(w, id=w.stem, marks=pytest.mark.zendock(world=str(w), **GRACEFUL)) for w in WORLDS]
)
def test_graceful_controller_docks_in_every_shipped_world(
    world: Path, zendock_stack: ZendockStack, zendock_robot: Robot
) -> None:
    """Process per service, through the plugin: low battery, then CHARGING, mated on ground truth."""
    zendock_robot.wait_for(topics.BATTERY_STATUS, timeout_s=30.0, what="(the battery service publishing)")
    zendock_robot.set_battery(LOW_BATTERY)
    zendock_robot.wait_for(
        topics.BATTERY_STATUS, is_charging, timeout_s=DOCK_WITHIN_S, what="saying CHARGING"
    )
    truth = zendock_robot.sim_state()
    contact = truth.contact
    assert contact.mated, f"charging but not mated on ground truth: {truth}"
    assert truth.collisions == 0, truth
    assert abs(contact.lateral_error_m) < 0.04 and abs(contact.yaw_error_rad) < 0.1, truth


#: The composed robot is the same code in one process: every world docks process-per-service above, and the
#: composed robot docks in two of them (glass found late, an angled dock) beside the seed controller's room.
COMPOSED_WORLDS = [w for w in WORLDS if w.stem in ("glass_room", "angled_dock")]


@pytest.mark.parametrize("world", COMPOSED_WORLDS, ids=lambda p: p.stem)
def test_graceful_controller_docks_composed(world: Path, tmp_path: Path) -> None:
    report = run_demo(
        DemoOptions(
            world=world,
            controller="graceful",
            rtf="4",
            runs_dir=tmp_path,
            localisation_error=(0.03, -0.02, 0.02),
            compose=True,
        ),
        log=lambda _t: None,
    )
    _assert_docked(report, tmp_path)
    _no_stack_left(tmp_path)
