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
        wait_until(
            lambda: (
                launcher.status("battery").starts > before and launcher.status("battery").health == "healthy"
            ),
            30.0,
            lambda: f"battery not back: {launcher.status('battery')}",
        )
        battery.wait_for(after=battery.count, timeout_s=20.0)
        assert launcher.status("battery").restarts >= 1
        assert launcher.status("simulator").restarts == 0 and launcher.status("pose").restarts == 0


def test_a_killed_group_restarts_with_all_its_services_and_ps_names_them(tmp_path, namespace: str) -> None:  # type: ignore[no-untyped-def]
    from deploy.launcher import Launcher, free_endpoint, load_stack
    from tests.support.processes import REPO_ROOT

    endpoint = free_endpoint()
    stack = load_stack(
        REPO_ROOT / "deploy" / "stack.yaml",
        project_dir=REPO_ROOT,
        env={"ZENOH_LISTEN": endpoint, "ZENOH_CONNECT": endpoint, "ZENDOCK_RTF": "2"},
        compose={"light": ["battery", "pose"]},
    )
    with (
        Launcher(
            stack,
            services=("router", "simulator", "light"),
            project_dir=tmp_path / "stack",
            working_dir=REPO_ROOT,
            namespace=namespace,
            project_name="group",
        ) as launcher,
        open_session(SessionSpec(connect=(endpoint,))) as session,
    ):
        launcher.wait_healthy(timeout_s=60.0)
        assert launcher.status("light").members == ["battery", "pose"]
        pose = KeyRecorder(session, f"{namespace}/map_to_base_link_pose2d", Float64MultiArray)
        battery = KeyRecorder(session, f"{namespace}/battery_status", BatteryState)
        pose.wait_for(timeout_s=30.0)
        battery.wait_for(timeout_s=30.0)
        before = launcher.status("light").starts
        launcher.kill("light")
        wait_until(
            lambda: launcher.status("light").starts > before and launcher.status("light").health == "healthy",
            30.0,
            lambda: f"the group is not back: {launcher.status('light')}",
        )
        pose.wait_for(after=pose.count, timeout_s=20.0)  # both of its services are back
        battery.wait_for(after=battery.count, timeout_s=20.0)
        status = launcher.status("light")
        assert status.restarts >= 1 and status.members == ["battery", "pose"]
        assert status.ps_json()["members"] == ["battery", "pose"]
        assert launcher.status("simulator").restarts == 0
