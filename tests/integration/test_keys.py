"""``zendock keys`` against live publishers on a real router: every verb, and bad payloads on a key.

The test starts its own small "talker" node (Twist at 20 Hz, a stamped BatteryState at 10 Hz, a Twist
subscription, and two keys carrying bad payloads) and runs the CLI in-process through deploy.cli.main.
"""

from __future__ import annotations

import io
import json
import math
import os
import subprocess
import sys
import threading
import time
from collections.abc import Iterator

import msgpack
import pytest
import yaml
import zenoh

from deploy import cli
from deploy.keys.connection import bus_options
from deploy.keys.pub import PubRequest, run_pub
from shared.interface_types import CANCEL_GOAL, CancelGoalResponse
from shared.messages import BatteryState, Clock, Time, Twist, now_header
from shared.names import endpoint_token_key
from shared.node import Node, encoding_for
from shared.session import SessionSpec, open_session
from tests.support.bus import KeyRecorder, liveliness_keys
from tests.support.processes import REPO_ROOT, free_port, wait_until

TWIST = "geometry_msgs/msg/Twist"
BATTERY = "sensor_msgs/msg/BatteryState"
TALKER_TWIST = Twist.planar(0.2, -0.1)
GARBAGE = b"\x0a\x0b\xc1\xff"


class Talker:
    """A node publishing on a few keys from its own executor thread, with the bad payloads tests need."""

    def __init__(self, session: zenoh.Session, namespace: str, clock_speed: float | None = None) -> None:
        self.node = Node("talker", session, namespace)
        self.namespace = namespace
        twist = self.node.create_publisher(Twist, "cmd_vel")
        battery = self.node.create_publisher(BatteryState, "battery_status")
        self.node.create_subscription(Twist, "cmd_in", lambda _msg: None)
        self.node.create_service(CANCEL_GOAL, "cancel_all", lambda _request: CancelGoalResponse())
        # an action's internal part: hidden from ``keys list`` unless -a, as ros2 hides _-prefixed names
        self.node.create_service(
            CANCEL_GOAL, "dock/_action/cancel_goal", lambda _request: CancelGoalResponse()
        )
        garbage = session.declare_publisher(f"{namespace}/garbage", encoding=encoding_for(TWIST))
        wrong_shape = session.declare_publisher(f"{namespace}/wrong_shape", encoding=encoding_for(TWIST))
        self.node.create_timer(0.05, lambda: twist.publish(TALKER_TWIST))
        self.node.create_timer(
            0.1,
            lambda: battery.publish(
                BatteryState(header=now_header("base_link"), percentage=0.5, voltage=12.5)
            ),
        )
        self.node.create_timer(0.1, lambda: garbage.put(GARBAGE))
        self.node.create_timer(0.1, lambda: wrong_shape.put(msgpack.packb({"linear": {"x": "fast"}})))
        if clock_speed is not None:
            clock = self.node.create_publisher(Clock, "clock")
            start = time.monotonic()
            self.node.create_timer(
                0.01, lambda: clock.publish(Clock(Time.from_sec((time.monotonic() - start) * clock_speed)))
            )
        self.node.declare_ready()
        self._thread = threading.Thread(target=self.node.spin, name="talker", daemon=True)
        self._thread.start()

    def expected_tokens(self) -> set[str]:
        ns = self.namespace
        return {
            endpoint_token_key("pub", ns, "talker", TWIST, f"{ns}/cmd_vel"),
            endpoint_token_key("pub", ns, "talker", BATTERY, f"{ns}/battery_status"),
            endpoint_token_key("sub", ns, "talker", TWIST, f"{ns}/cmd_in"),
            endpoint_token_key("srv", ns, "talker", CANCEL_GOAL.type_name, f"{ns}/cancel_all"),
            endpoint_token_key("srv", ns, "talker", CANCEL_GOAL.type_name, f"{ns}/dock/_action/cancel_goal"),
        }

    def close(self) -> None:
        self.node.shutdown()
        self._thread.join(5)
        self.node.close()


def _start_talker(
    router_endpoint: str, bus: zenoh.Session, namespace: str, clock_speed: float | None
) -> Talker:
    talker = Talker(bus, namespace, clock_speed)
    with open_session(SessionSpec(mode="client", connect=(router_endpoint,))) as observer:
        wait_until(
            lambda: talker.expected_tokens() <= set(liveliness_keys(observer, timeout_s=0.5)),
            10.0,
            lambda: f"talker tokens not on the router: {liveliness_keys(observer)}",
        )
    return talker


@pytest.fixture
def talker(router_endpoint: str, bus: zenoh.Session, namespace: str) -> Iterator[Talker]:
    node = _start_talker(router_endpoint, bus, namespace, clock_speed=None)
    yield node
    node.close()


@pytest.fixture
def keys(router_endpoint: str, namespace: str, capsys: pytest.CaptureFixture[str]):  # type: ignore[no-untyped-def]
    """``keys("echo", "cmd_vel", "--once")`` -> ``(exit code, stdout, stderr)`` of ``zendock keys ...``."""

    def run(verb: str, *argv: str) -> tuple[int, str, str]:
        capsys.readouterr()
        code = cli.main(["keys", verb, "--connect", router_endpoint, "--namespace", namespace, *argv])
        captured = capsys.readouterr()
        return code, captured.out, captured.err

    return run


def _last_json(text: str) -> dict:
    return json.loads(text.strip().splitlines()[-1])


def test_list_shows_keys_types_and_nodes(talker: Talker, keys, namespace: str) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = keys("list")
    assert code == 0
    assert out.splitlines() == [
        f"{namespace}/battery_status",
        f"{namespace}/cancel_all (service)",
        f"{namespace}/cmd_in",
        f"{namespace}/cmd_vel",
    ]
    for flag in ("-a", "--include-hidden"):
        code, out, _ = keys("list", flag)
        assert code == 0 and f"{namespace}/dock/_action/cancel_goal (service)" in out.splitlines()
    code, out, _ = keys("list", "-t")
    assert f"{namespace}/cmd_vel [{TWIST}]" in out and f"{namespace}/battery_status [{BATTERY}]" in out
    code, out, _ = keys("list", "-v")
    lines = out.splitlines()
    at = lines.index(f"{namespace}/cmd_vel [{TWIST}]")
    assert lines[at + 1 : at + 3] == [f"  publishers (1): /{namespace}/talker", "  subscribers (0):"]
    assert f"  service servers (1): /{namespace}/talker" in lines
    code, out, _ = keys("info", "cancel_all")
    assert "Service server count: 1" in out and "Type: action_msgs/srv/CancelGoal" in out


def test_list_in_an_empty_namespace_says_so(talker: Talker, router_endpoint: str, capsys) -> None:  # type: ignore[no-untyped-def]
    code = cli.main(["keys", "list", "--connect", router_endpoint, "--namespace", "nobody_here"])
    captured = capsys.readouterr()
    assert code == 0 and captured.out == "" and "no keys announced in namespace 'nobody_here'" in captured.err


def test_info_counts_publishers_and_subscribers(talker: Talker, keys, namespace: str) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = keys("info", "/cmd_vel")
    assert code == 0
    assert out.splitlines() == [
        f"Key: {namespace}/cmd_vel",
        f"Type: {TWIST}",
        "Publisher count: 1",
        f"    /{namespace}/talker",
        "Subscription count: 0",
    ]
    code, out, _ = keys("info", "cmd_in")
    assert "Publisher count: 0" in out and "Subscription count: 1" in out
    code, _, err = keys("info", "no_such_key")
    assert code == 1 and f"unknown key '{namespace}/no_such_key'" in err and len(err.splitlines()) == 1


def test_echo_once_decodes_the_message(talker: Talker, keys) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = keys("echo", "/cmd_vel", "--once")
    assert code == 0 and out.rstrip().endswith("---")
    assert yaml.safe_load(out.split("---")[0]) == {
        "linear": {"x": 0.2, "y": 0.0, "z": 0.0},
        "angular": {"x": 0.0, "y": 0.0, "z": -0.1},
    }
    code, out, _ = keys("echo", "battery_status", "--times", "2", "--field", "header.frame_id")
    assert code == 0 and out.split() == ["base_link", "---", "base_link", "---"]
    code, out, _ = keys("echo", "cmd_vel", "--once", "--csv")
    assert out.strip() == "0.2,0.0,0.0,0.0,0.0,-0.1"


def test_echo_shows_bad_payloads_without_crashing(talker: Talker, keys, namespace: str) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = keys("echo", "garbage", "--times", "2")
    assert code == 0
    assert out.split("\n---\n")[0] == "<4 bytes, not msgpack: 0a0bc1ff>"
    code, out, _ = keys("echo", "wrong_shape", "--once")
    assert code == 0
    assert out.startswith(f"# not a valid {TWIST}: field 'linear.x': expected a number, got str")
    assert "linear:\n  x: fast" in out
    code, out, _ = keys("echo", "garbage", "--once", "--raw")
    assert out.split() == [GARBAGE.hex(), "---"]
    code, out, _ = keys("echo", "**", "--times", "12")  # every key, good and bad, each labelled
    assert (
        code == 0 and f"# {namespace}/garbage [{TWIST}]" in out and f"# {namespace}/cmd_vel [{TWIST}]" in out
    )


def test_echo_errors(talker: Talker, keys, namespace: str) -> None:  # type: ignore[no-untyped-def]
    code, out, err = keys("echo", "silent_key", "--once", "--timeout", "0.5")
    assert code == 1 and out == "" and f"no message on {namespace}/silent_key within 0.5 s" in err
    code, _, err = keys("echo", "cmd_vel", "--once", "--field", "linear.q")
    assert code == 2 and "no field 'q' in linear" in err


def test_hz_reports_the_publishing_rate(talker: Talker, keys, namespace: str) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = keys("hz", "cmd_vel", "battery_status", "--duration", "2", "--json")
    assert code == 0
    summary = _last_json(out)["keys"]
    assert 10 < summary[f"{namespace}/cmd_vel"]["rate_hz"] < 30
    assert 5 < summary[f"{namespace}/battery_status"]["rate_hz"] < 15
    assert summary[f"{namespace}/cmd_vel"]["count"] >= 10


def test_hz_prints_like_ros2_and_fails_on_silence(talker: Talker, keys, namespace: str) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = keys("hz", "cmd_vel", "silent_key", "--duration", "1.2", "-w", "5")
    assert code == 1
    assert f"{namespace}/cmd_vel:\naverage rate: " in out and "window: 6" in out
    assert f"{namespace}/silent_key:\nno new messages" in out


def test_hz_on_sim_time(router_endpoint: str, bus: zenoh.Session, namespace: str, keys) -> None:  # type: ignore[no-untyped-def]
    talker = _start_talker(router_endpoint, bus, namespace, clock_speed=2.0)
    try:
        code, out, _ = keys("hz", "cmd_vel", "--sim-time", "--duration", "1.5", "--json")
    finally:
        talker.close()
    assert code == 0
    # 20 Hz of wall time is 10 Hz of a clock running twice as fast
    assert 6 < _last_json(out)["keys"][f"{namespace}/cmd_vel"]["rate_hz"] < 15


def test_hz_on_sim_time_without_a_clock_is_an_error(talker: Talker, keys, namespace: str) -> None:  # type: ignore[no-untyped-def]
    code, _, err = keys("hz", "cmd_vel", "--sim-time", "--duration", "0.5")
    assert code == 1 and f"no time on {namespace}/clock" in err


def test_bw_measures_bytes(talker: Talker, keys, namespace: str) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = keys("bw", "cmd_vel", "--duration", "1.2", "--json")
    assert code == 0
    summary = _last_json(out)["keys"][f"{namespace}/cmd_vel"]
    assert summary["bytes_per_s"] > 0
    assert summary["min_bytes"] == summary["max_bytes"] == len(TALKER_TWIST.encode())


def test_delay_against_the_header_stamp(talker: Talker, keys, namespace: str) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = keys("delay", "battery_status", "--duration", "1.2", "--json")
    assert code == 0
    summary = _last_json(out)["keys"][f"{namespace}/battery_status"]
    assert math.isfinite(summary["average_s"]) and -0.05 < summary["average_s"] < 1.0
    code, _, err = keys("delay", "cmd_vel", "--duration", "1.2")
    assert code == 1 and "has no header.stamp" in err


def test_pub_validates_before_sending(talker: Talker, keys, bus: zenoh.Session, namespace: str) -> None:  # type: ignore[no-untyped-def]
    recorder = KeyRecorder(bus, f"{namespace}/cmd_in", Twist)
    try:
        code, out, err = keys("pub", "cmd_in", "{linear: {q: 0.3}}", "--once")
        assert code == 2 and out == ""
        assert "field 'linear.q'" in err and len(err.splitlines()) == 1
        code, out, err = keys("pub", "/cmd_in", "{linear: {x: 0.3}}", "--times", "3", "--rate", "50")
        assert code == 0, err
        assert out.count("publishing #") == 3  # TYPE came from the talker's subscription token
        recorder.wait_for(lambda m: True, timeout_s=5.0, after=2)
        assert recorder.count == 3 and recorder.errors == []
        assert all(m == Twist.planar(0.3, 0.0) for m in recorder.messages)
    finally:
        recorder.close()


def test_pub_needs_a_type_nobody_announced(talker: Talker, keys) -> None:  # type: ignore[no-untyped-def]
    code, _, err = keys("pub", "fresh_key", "{data: 1.5}", "--once")
    assert code == 2 and "give TYPE" in err
    code, _, err = keys(
        "pub", "fresh_key", "std_msgs/msg/Float64", "{data: 1.5}", "--once", "--wait-matching", "0.2"
    )
    assert code == 0 and "no subscriber on" in err


def test_pub_declares_its_own_token(talker: Talker, router_endpoint: str, namespace: str, keys) -> None:  # type: ignore[no-untyped-def]
    stop = threading.Event()
    options = bus_options([router_endpoint], namespace)
    request = PubRequest(key="cmd_vel", values_yaml="{angular: {z: 0.5}}", rate_hz=20.0, quiet=True)
    publisher = threading.Thread(target=run_pub, args=(options, request, io.StringIO(), None, stop))
    publisher.start()
    token = endpoint_token_key("pub", namespace, f"keys_pub_{os.getpid()}", TWIST, f"{namespace}/cmd_vel")
    try:
        with open_session(SessionSpec(mode="client", connect=(router_endpoint,))) as observer:
            wait_until(
                lambda: token in liveliness_keys(observer, timeout_s=0.5), 10.0, "no token from keys pub"
            )
        code, out, _ = keys("info", "cmd_vel")
        assert code == 0 and "Publisher count: 2" in out and f"/{namespace}/keys_pub_{os.getpid()}" in out
    finally:
        stop.set()
        publisher.join(5)
    assert not publisher.is_alive()


def test_admin_space_shows_keys_without_tokens(namespace: str, capsys) -> None:  # type: ignore[no-untyped-def]
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    router = SessionSpec(
        mode="router", connect=(), listen=(endpoint,), overrides=(("adminspace/enabled", "true"),)
    )
    with open_session(router), open_session(SessionSpec(mode="client", connect=(endpoint,))) as session:
        raw = session.declare_publisher(f"{namespace}/raw_camera")
        wait_until(
            lambda: any(r.ok is not None for r in session.get(f"@/*/router/publisher/{namespace}/**")),
            10.0,
            "the router's admin space never listed the publisher",
        )
        code = cli.main(["keys", "list", "-t", "--connect", endpoint, "--namespace", namespace])
        raw.undeclare()
    assert code == 0
    assert capsys.readouterr().out.splitlines() == [f"{namespace}/raw_camera [?] (no token)"]


def test_unreachable_router_is_one_line_and_exit_1() -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    started = time.monotonic()
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "deploy.cli",
            "keys",
            "echo",
            "cmd_vel",
            "--once",
            "--connect",
            endpoint,
            "--connect-timeout",
            "1",
        ],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 1, result.stderr
    assert result.stderr.startswith(
        f"zendock keys echo: cannot reach a Zenoh router at {endpoint} within 1 s"
    )
    assert len(result.stderr.strip().splitlines()) == 1 and result.stdout == ""
    assert time.monotonic() - started < 15
