"""The argparse layer and the pure parts of list, info, pub, hz and delay."""

from __future__ import annotations

import argparse

import pytest

from deploy.commands import keys as keys_command
from deploy.keys.delay import DelayStats, header_stamp_s
from deploy.keys.errors import KeysError
from deploy.keys.graph import build_graph
from deploy.keys.hz import RateStats
from deploy.keys.info import info_lines
from deploy.keys.listing import ListFormat, is_hidden, list_lines
from deploy.keys.monitor import MonitorRequest
from deploy.keys.pub import split_type_and_values
from deploy.keys.sampling import ReceivedSample
from shared.messages import BatteryState, Twist, now_header
from shared.names import endpoint_token_key

TWIST = "geometry_msgs/msg/Twist"


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="zendock")
    keys_command.register(parser.add_subparsers(dest="command"))
    return parser.parse_args(["keys", *argv])


def test_every_verb_takes_the_bus_flags() -> None:
    for verb, extra in [
        ("list", []),
        ("echo", ["k"]),
        ("hz", ["k"]),
        ("bw", ["k"]),
        ("delay", ["k"]),
        ("info", ["k"]),
        ("pub", ["k"]),
    ]:
        args = _parse(
            verb, *extra, "--connect", "tcp/1.2.3.4:7447", "--namespace", "r1", "--connect-timeout", "1"
        )
        assert (args.connect, args.namespace, args.connect_timeout) == (["tcp/1.2.3.4:7447"], "r1", 1.0)
        assert callable(args.func)


def test_echo_and_hz_flags() -> None:
    echo = _parse("echo", "/cmd_vel", "--once", "--field", "linear.x", "--csv", "--timeout", "2")
    assert (echo.key, echo.once, echo.field, echo.csv, echo.timeout) == (
        "/cmd_vel",
        True,
        "linear.x",
        True,
        2.0,
    )
    hz = _parse("hz", "a", "b", "-w", "50", "--sim-time", "--duration", "3", "--json")
    assert (hz.keys, hz.window, hz.sim_time, hz.duration, hz.json) == (["a", "b"], 50, True, 3.0, True)
    with pytest.raises(SystemExit):
        _parse("echo", "k", "--csv", "--raw")
    with pytest.raises(SystemExit):
        _parse("bw", "k", "--sim-time")  # bandwidth does not depend on a clock


def test_pub_arguments() -> None:
    args = _parse(
        "pub", "cmd_vel", "geometry_msgs/msg/Twist", "{linear: {x: 0.2}}", "--rate", "5", "--times", "3"
    )
    assert (args.key, args.type_and_values, args.rate, args.times) == (
        "cmd_vel",
        ["geometry_msgs/msg/Twist", "{linear: {x: 0.2}}"],
        5.0,
        3,
    )
    assert _parse("pub", "cmd_vel", "{}", "-1").once


@pytest.mark.parametrize(
    ("arguments", "expected"),
    [
        ([], (None, "")),
        (["{linear: {x: 0.2}}"], (None, "{linear: {x: 0.2}}")),
        (["geometry_msgs/msg/Twist"], ("geometry_msgs/msg/Twist", "")),
        (["Twist"], ("Twist", "")),
        (["data: 3"], (None, "data: 3")),
        (["Twist", "{}"], ("Twist", "{}")),
    ],
)
def test_type_is_optional_before_the_values(arguments: list[str], expected: tuple) -> None:
    assert split_type_and_values(arguments) == expected


def test_too_many_pub_arguments_is_a_usage_error() -> None:
    with pytest.raises(KeysError, match="quote the YAML"):
        split_type_and_values(["Twist", "linear:", "x"])


def _graph():  # type: ignore[no-untyped-def]
    return build_graph(
        [
            endpoint_token_key("pub", "r1", "teleop", TWIST, "r1/cmd_vel"),
            endpoint_token_key("sub", "r1", "sim", TWIST, "r1/cmd_vel"),
            endpoint_token_key("srv", "r1", "sim", "zendock_msgs/srv/Teleport", "r1/simulator/teleport"),
            endpoint_token_key("act", "r1", "docking", "zendock_msgs/action/DockRobot", "r1/dock_robot"),
        ],
        [("pub", "r1/raw")],
    )


def test_list_plain_types_and_verbose() -> None:
    entries = _graph().in_namespace("r1")
    assert list_lines(entries, ListFormat()) == [
        "r1/cmd_vel",
        "r1/dock_robot (action)",
        "r1/raw (no token)",
        "r1/simulator/teleport (service)",
    ]
    typed = list_lines(entries, ListFormat(show_types=True))
    assert typed[0] == f"r1/cmd_vel [{TWIST}]" and typed[2] == "r1/raw [?] (no token)"
    verbose = list_lines(entries, ListFormat(verbose=True))
    assert verbose[:3] == [
        f"r1/cmd_vel [{TWIST}]",
        "  publishers (1): /r1/teleop",
        "  subscribers (1): /r1/sim",
    ]
    assert "  action servers (1): /r1/docking" in verbose
    assert "  service servers (1): /r1/sim" in verbose
    assert "  without a zendock token (router admin space): publisher" in verbose


def test_hidden_keys_are_those_ros2_hides() -> None:
    assert (
        is_hidden("r1/dock_robot/_action/status")
        and is_hidden("r1/battery/_param/get")
        and is_hidden("_internal")
    )
    assert not is_hidden("r1/dock_robot") and not is_hidden("r1/cmd_vel") and not is_hidden("r1/a_b")
    for flag in ("-a", "--include-hidden", "--include-hidden-topics"):
        assert _parse("list", flag).include_hidden
    assert not _parse("list").include_hidden


def test_info_counts_and_nodes() -> None:
    graph = _graph()
    assert info_lines(graph.keys["r1/cmd_vel"]) == [
        "Key: r1/cmd_vel",
        f"Type: {TWIST}",
        "Publisher count: 1",
        "    /r1/teleop",
        "Subscription count: 1",
        "    /r1/sim",
    ]
    service = info_lines(graph.keys["r1/simulator/teleport"])
    assert "Service server count: 1" in service and "Publisher count: 0" in service
    assert info_lines(graph.keys["r1/raw"])[1] == "Type: unknown (no zendock token)"


def _sample(payload: bytes, encoding: str, wall_s: float = 0.0, monotonic_s: float = 0.0) -> ReceivedSample:
    return ReceivedSample("k", payload, encoding, None, wall_s, monotonic_s)


def test_hz_uses_sim_time_when_given() -> None:
    stats = RateStats("k", 100)
    for i in range(5):  # wall arrivals 0.1 s apart, sim time 0.2 s apart: 5 Hz in sim time
        stats.add(_sample(b"", "", monotonic_s=i * 0.1), sim_now_s=i * 0.2)
    summary = stats.summary(0.0)
    assert summary is not None and summary.rate_hz == pytest.approx(5.0) and stats.count == 5


def test_delay_reads_header_stamp_and_skips_bad_payloads() -> None:
    stats = DelayStats("k", 100)
    encoding = "application/msgpack;sensor_msgs/msg/BatteryState"
    stats.add(_sample(BatteryState(header=now_header("base", 10.0)).encode(), encoding, wall_s=10.25), None)
    stats.add(_sample(b"\xc1", encoding, wall_s=11.0), None)
    stats.add(_sample(BatteryState(header=now_header("base", 20.0)).encode(), encoding, wall_s=99.0), 20.5)
    summary = stats.summary(0.0)
    assert summary is not None and summary.window == 2 and stats.skipped == 1
    assert (summary.min_s, summary.max_s) == pytest.approx((0.25, 0.5))


def test_delay_refuses_messages_without_a_stamp() -> None:
    stats = DelayStats("k", 100)
    with pytest.raises(KeysError, match="has no header.stamp"):
        stats.add(_sample(Twist().encode(), f"application/msgpack;{TWIST}"), None)
    assert header_stamp_s({"header": {"stamp": {"sec": 1, "nanosec": 500_000_000}}}) == 1.5
    assert header_stamp_s({"header": {"stamp": {"sec": "1"}}}) is None
    assert header_stamp_s([1, 2]) is None


@pytest.mark.parametrize(
    ("request_", "reason"),
    [
        (MonitorRequest(keys=(), window=10), "at least one key"),
        (MonitorRequest(keys=("k",), window=0), "--window"),
        (MonitorRequest(keys=("k",), window=10, duration_s=-1), "--duration"),
    ],
)
def test_monitor_flags_are_checked(request_: MonitorRequest, reason: str) -> None:
    with pytest.raises(KeysError, match=reason):
        request_.check()
