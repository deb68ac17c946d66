"""Test your own docking service against a whole zendock stack: copy this file next to your code.

zendock's pytest plugin loads by itself once zendock is installed (``pip install zendock``). Each test
below gets a fresh stack (router on a free port, simulator, perception, battery, pose, planner) in which
your program runs in place of zendock's docking service, with the flags zendock's own would get
(``-p use_sim_time=true -p dock_database=<world> -p controller=...``). If a test fails, the report shows
the last lines of every service's log, yours included.

Run:  pytest examples/tests            (add --zendock-rtf 2 on a slow machine)

Paths in ``services`` are relative to the pytest root directory (where pytest.ini or pyproject.toml is).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.testing import Robot, ZendockStack, is_charging

MY_DOCKING = "examples/docking/docking.py"
ROOT = Path(__file__).resolve().parents[2]

pytestmark = [
    pytest.mark.skipif(not (ROOT / MY_DOCKING).is_file(), reason=f"{MY_DOCKING} does not exist yet"),
    pytest.mark.zendock(world="seed_room", detector="synthetic", rtf=4,
                        services={"docking": f"python {MY_DOCKING}"}),
]


def test_docks_by_itself_when_the_battery_runs_low(zendock_stack: ZendockStack, zendock_robot: Robot) -> None:
    zendock_robot.wait_for("battery_status", timeout_s=30.0, what="(the battery publishing)")
    zendock_robot.set_battery(0.2)  # below the 0.25 threshold: the docking service must go home
    zendock_robot.wait_for("battery_status", is_charging, timeout_s=200.0, what="saying CHARGING")
    truth = zendock_robot.sim_state()  # the simulator's ground truth, not the robot's belief
    assert truth.contact.mated, truth
    assert truth.collisions == 0, truth
    assert abs(truth.contact.lateral_error_m) < 0.04 and abs(truth.contact.yaw_error_rad) < 0.1, truth


def test_docks_and_undocks_on_request(zendock_stack: ZendockStack, zendock_robot: Robot) -> None:
    docked = zendock_robot.dock(timeout_s=200.0)  # dock_robot to the nearest dock
    assert docked.success, docked
    zendock_robot.wait_for("battery_status", is_charging, timeout_s=30.0, what="saying CHARGING")
    undocked = zendock_robot.undock(timeout_s=60.0)
    assert undocked.success, undocked
    zendock_robot.wait_for("battery_status", lambda b: not is_charging(b), timeout_s=30.0, what="no longer charging")
    assert not zendock_robot.sim_state().contact.mated
