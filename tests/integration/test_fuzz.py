"""``zendock fuzz`` against live services: they survive, keep publishing, answer, and log rejections sparingly."""

from __future__ import annotations

import json
import re
import time
from collections import Counter

import pytest
import zenoh

from deploy.cli import main
from deploy.fuzz import FuzzOptions, run_fuzz
from shared.interfaces.simulator import SIM_STATE, SimStateRequest
from shared.messages import BatteryState, Clock, Float64MultiArray, String
from shared.node import call_service
from tests.support.bus import KeyRecorder, liveliness_keys
from tests.support.processes import REPO_ROOT, free_port, wait_until

SEED_ROOM = str(REPO_ROOT / "deploy/worlds/seed_room.yaml")
MESSAGES = 5000
REJECTED = re.compile(r"rejected message on (\S+) \(")
#: RateLimitedLogger's interval in shared.node: one line per key per 5 s at most.
LOG_INTERVAL_S = 5.0


def test_services_survive_malformed_input(  # type: ignore[no-untyped-def]
    spawn, bus: zenoh.Session, router_endpoint: str, namespace: str, capsys: pytest.CaptureFixture[str]
) -> None:
    services = {
        "simulator": spawn("simulator", "--world", SEED_ROOM, "-p", "rtf=2"),
        "battery": spawn("battery", "-p", "use_sim_time=true"),
        "pose": spawn("pose", "-p", "use_sim_time=true"),
        "docking": spawn("docking", "-p", f"dock_database={SEED_ROOM}", "-p", "use_sim_time=true"),
    }
    streams = {
        "simulator": KeyRecorder(bus, f"{namespace}/clock", Clock),
        "battery": KeyRecorder(bus, f"{namespace}/battery_status", BatteryState),
        "pose": KeyRecorder(bus, f"{namespace}/map_to_base_link_pose2d", Float64MultiArray),
        "docking": KeyRecorder(bus, f"{namespace}/docking/state", String),
    }
    nodes = {f"@zendock/node/{namespace}/{name}" for name in services}
    wait_until(
        lambda: nodes <= set(liveliness_keys(bus, f"@zendock/node/{namespace}/*")),
        30.0,
        lambda: f"ready: {liveliness_keys(bus, f'@zendock/node/{namespace}/*')}",
    )

    report = run_fuzz(
        FuzzOptions(
            connect=(router_endpoint,), namespace=namespace, messages=MESSAGES, seed=7, time_limit_s=20.0
        )
    )
    summary = report.as_dict()
    assert summary["sent"] == MESSAGES and summary["stopped_by"] == "count", summary
    assert summary["decoder_errors"] == 0, {
        k: v["decoder_errors"] for k, v in summary["keys"].items() if "decoder_errors" in v
    }
    keys = summary["keys"]
    for key in (
        "cmd_vel",
        "odom",
        "tf",
        "clock",
        "scan",
        "battery_status",
        "simulator/teleport",
        "dock_robot/_action/send_goal",
        "dock_robot/_action/get_result",
        "undock_robot/_action/cancel_goal",
    ):
        entry = keys[f"{namespace}/{key}"]
        assert entry["announced"] and entry["type"] and entry["sent"] > 50, (key, entry)
    assert {"missing_field", "wrong_type", "non_finite", "out_of_range", "truncated", "wrong_schema"} <= set(
        summary["kinds"]
    )
    # every malformed request got an error reply, none was answered as valid
    assert summary["replies"]["ok"] == 0, summary["replies"]
    teleport = keys[f"{namespace}/simulator/teleport"]["replies"]
    assert teleport["error"] == keys[f"{namespace}/simulator/teleport"]["sent"], teleport
    fuzz_ended = time.monotonic()

    # still alive, still publishing valid messages, still answering a valid request
    for name, proc in services.items():
        assert proc.alive(), f"{name} died:\n{proc.output()[-3000:]}"
    for stream in streams.values():  # valid ones only: the fuzz's own messages on these keys do not count
        stream.wait_for(after=stream.count + 2, timeout_s=15.0)
    state = call_service(bus, f"{namespace}/simulator/state", SIM_STATE, SimStateRequest(), timeout_s=5.0)
    assert state.world

    # rejections were logged, rate-limited: a line or two per key, not one per message
    elapsed_s = time.monotonic() - fuzz_ended + report.elapsed_s
    most_lines_per_key = int(elapsed_s / LOG_INTERVAL_S) + 2
    for name, proc in services.items():
        log = proc.output()
        assert "callback failed" not in log and "Traceback" not in log, f"{name}:\n{log[-3000:]}"
        lines = Counter(REJECTED.findall(log))
        assert lines, f"{name} logged no rejection:\n{log[-2000:]}"
        for key, count in lines.items():
            assert count <= most_lines_per_key < keys[key]["sent"] / 10, (name, key, count, keys[key]["sent"])

    # the command line: a short run, reported as JSON
    capsys.readouterr()
    code = main(
        ["fuzz", "--connect", router_endpoint, "--namespace", namespace, "--messages", "300", "--json"]
    )
    printed = json.loads(capsys.readouterr().out)
    assert code == 0 and printed["sent"] == 300 and printed["announced_targets"] >= 20, printed
    assert all(proc.alive() for proc in services.values())


def test_no_router_is_one_clear_line(capsys: pytest.CaptureFixture[str]) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    assert main(["fuzz", "--connect", endpoint, "--messages", "10"]) == 1
    assert f"cannot reach a Zenoh router at {endpoint}" in capsys.readouterr().err
