"""The robot handle on a bare router (no stack): waits that see the latest message or the next, fail saying
what came, and actions that fail at once when no server answers."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from deploy.testing.robot import Robot, WaitTimeout, is_charging
from shared import topics
from shared.messages import BatteryState, Float64MultiArray, String


@pytest.fixture
def robot(router_endpoint: str, namespace: str) -> Iterator[Robot]:
    handle = Robot(router_endpoint, namespace)
    try:
        yield handle
    finally:
        handle.close()


def test_battery_and_pose_are_the_latest_messages(robot: Robot) -> None:
    assert robot.battery is None and robot.pose is None
    robot.publish(topics.BATTERY_STATUS, BatteryState(percentage=0.5))
    robot.publish(topics.BATTERY_STATUS, BatteryState(percentage=0.4, power_supply_status=1))
    robot.publish(topics.POSE2D, Float64MultiArray(data=[1.0, 2.0, 0.5]))
    charging = robot.wait_for(topics.BATTERY_STATUS, is_charging, timeout_s=5.0)
    assert charging.percentage == pytest.approx(0.4)
    robot.wait_for(topics.POSE2D, timeout_s=5.0)
    assert robot.battery is not None and robot.battery.percentage == pytest.approx(0.4)
    assert robot.pose == [1.0, 2.0, 0.5]
    # the condition already holds: the latest message answers at once
    started = time.monotonic()
    assert robot.wait_for(topics.BATTERY_STATUS, is_charging, timeout_s=5.0).percentage == pytest.approx(0.4)
    assert time.monotonic() - started < 1.0


def test_a_wait_that_runs_out_says_what_arrived(robot: Robot) -> None:
    robot.watch("docking/state")
    robot.publish("docking/state", String(data="NAV_TO_STAGING_POSE"))
    robot.wait_for("docking/state", timeout_s=5.0)
    with pytest.raises(
        WaitTimeout,
        match=r"docking/state matching the condition within 0.3 s; 1 message\(s\) "
        r"arrived, 0 undecodable; the last: .*NAV_TO_STAGING_POSE",
    ):
        robot.wait_for("docking/state", lambda m: m.data == "CHARGING", timeout_s=0.3)


def test_actions_fail_at_once_without_a_server(robot: Robot) -> None:
    with pytest.raises(WaitTimeout, match="no dock_robot server in namespace"):
        robot.dock(server_timeout_s=0.3)
    with pytest.raises(WaitTimeout, match="no navigation server"):
        robot.nav(1.0, 0.0, 0.0, server_timeout_s=0.3)
    with pytest.raises(WaitTimeout, match="battery/set_state: no answer within 0.5 s"):
        robot.set_battery(0.2, timeout_s=0.5)
