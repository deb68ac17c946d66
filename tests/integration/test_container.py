"""``zendock container``: services composed in one process publish, answer and stop as they do alone."""

from __future__ import annotations

import signal
from pathlib import Path

import zenoh

from shared.messages import BatteryState, Float64MultiArray
from shared.names import node_token_key
from tests.support.bus import KeyRecorder
from tests.support.processes import REPO_ROOT, ServiceProcess, wait_until

SEED_ROOM = str(REPO_ROOT / "deploy/worlds/seed_room.yaml")


def test_a_group_runs_each_service_on_its_own_node_and_stops_cleanly(
    spawn,
    bus: zenoh.Session,
    namespace: str,  # type: ignore[no-untyped-def]
    router_endpoint: str,
    tmp_path: Path,
) -> None:
    battery = KeyRecorder(bus, f"{namespace}/battery_status", BatteryState)
    pose = KeyRecorder(bus, f"{namespace}/map_to_base_link_pose2d", Float64MultiArray)
    spawn("simulator", "--world", SEED_ROOM, "-p", "rtf=2")
    group = ServiceProcess(
        "deploy.cli",
        [
            "container",
            "--namespace",
            namespace,
            "--connect",
            router_endpoint,
            "battery",
            "-p",
            "use_sim_time=true",
            "+",
            "pose",
            "-p",
            "use_sim_time=true",
        ],
        tmp_path / "container.log",
    )
    try:
        battery.wait_for(timeout_s=30.0)
        pose.wait_for(
            timeout_s=30.0
        )  # pose hears the simulator's tf through the router, in one session with battery

        def tokens() -> set[str]:
            return {
                str(r.ok.key_expr)
                for r in bus.liveliness().get(node_token_key(namespace, "*"), timeout=2.0)
                if r.ok is not None
            }

        wanted = {node_token_key(namespace, name) for name in ("battery", "pose", "simulator")}
        wait_until(lambda: wanted <= tokens(), 10.0, lambda: sorted(tokens()))
        assert f"[{namespace}/battery] ready in a group of 2" in group.output()
        assert group.proc is not None
        group.proc.send_signal(signal.SIGTERM)
        assert group.proc.wait(15) == 0, group.output()[-2000:]
        out = group.output()
        assert f"[{namespace}/battery] stopped" in out and f"[{namespace}/pose] stopped" in out, out[-2000:]
        wait_until(
            lambda: not (wanted - {node_token_key(namespace, "simulator")}) & tokens(),
            10.0,
            lambda: sorted(tokens()),
        )
    finally:
        group.stop()
