"""The world services brought up the way users do (the launcher and the default stack), then a crash."""

from __future__ import annotations

from shared.messages import BatteryState, Float64MultiArray
from shared.session import SessionSpec, open_session
from tests.support.bus import KeyRecorder
from tests.support.processes import wait_until


def test_a_killed_service_is_restarted_and_the_others_never_stop(launch_stack, namespace: str) -> None:  # type: ignore[no-untyped-def]
    launcher, endpoint = launch_stack("simulator", "battery", "pose", env={"ZENDOCK_RTF": "2"})
    with open_session(SessionSpec(connect=(endpoint,))) as session:
        pose = KeyRecorder(session, f"{namespace}/map_to_base_link_pose2d", Float64MultiArray)
        battery = KeyRecorder(session, f"{namespace}/battery_status", BatteryState)
        pose.wait_for(timeout_s=30.0)
        battery.wait_for(timeout_s=30.0)
        before = launcher.status("battery").starts
        launcher.kill("battery")
        seen = pose.count
        pose.wait_for(after=seen + 5, timeout_s=20.0)  # pose keeps publishing while battery is down
        wait_until(lambda: launcher.status("battery").starts > before and launcher.status("battery").health == "healthy",
                   30.0, lambda: f"battery not back: {launcher.status('battery')}")
        battery.wait_for(after=battery.count, timeout_s=20.0)
        assert launcher.status("battery").restarts >= 1
        assert launcher.status("simulator").restarts == 0 and launcher.status("pose").restarts == 0
