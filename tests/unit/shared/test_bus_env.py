"""One reading of where the bus is: flags, then ZENDOCK_CONNECT, then ZENOH_CONNECT (and ZENOH_LISTEN)."""

from __future__ import annotations

import pytest

from deploy.keys.connection import resolve_endpoints
from shared.bus_env import connect_from_env, listen_from_env
from shared.runtime import build_arg_parser, options_from_args
from shared.session import DEFAULT_ROUTER_ENDPOINT


def test_zendock_connect_wins_over_zenoh_connect_and_lists_are_comma_separated() -> None:
    both = {"ZENDOCK_CONNECT": "tcp/127.0.0.1:7001", "ZENOH_CONNECT": "tcp/127.0.0.1:7002"}
    assert connect_from_env(both) == ("tcp/127.0.0.1:7001",)
    assert connect_from_env({"ZENOH_CONNECT": " tcp/127.0.0.1:7002, tcp/127.0.0.1:7003 "}) == (
        "tcp/127.0.0.1:7002",
        "tcp/127.0.0.1:7003",
    )
    assert connect_from_env({"ZENDOCK_CONNECT": "", "ZENOH_CONNECT": "tcp/127.0.0.1:7002"}) == (
        "tcp/127.0.0.1:7002",
    )
    assert connect_from_env({}) == () and listen_from_env({"ZENOH_LISTEN": "tcp/127.0.0.1:7004"}) == (
        "tcp/127.0.0.1:7004",
    )


def test_a_cli_command_reads_the_same_and_its_flag_wins() -> None:
    env = {"ZENOH_CONNECT": "tcp/127.0.0.1:7002"}
    assert resolve_endpoints(None, env) == ("tcp/127.0.0.1:7002",)
    assert resolve_endpoints(["tcp/127.0.0.1:7009"], env) == ("tcp/127.0.0.1:7009",)
    assert resolve_endpoints(None, {}) == (DEFAULT_ROUTER_ENDPOINT,)


def test_a_service_started_by_hand_connects_where_zenoh_connect_says(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("ZENDOCK_CONNECT", raising=False)
    monkeypatch.setenv("ZENOH_CONNECT", "tcp/127.0.0.1:7002")
    args = build_arg_parser("viz").parse_args([])
    assert options_from_args(args).connect == ("tcp/127.0.0.1:7002",)
    monkeypatch.setenv("ZENDOCK_CONNECT", "tcp/127.0.0.1:7001")
    assert options_from_args(build_arg_parser("viz").parse_args([])).connect == ("tcp/127.0.0.1:7001",)
    flagged = build_arg_parser("viz").parse_args(["--connect", "tcp/127.0.0.1:7009"])
    assert options_from_args(flagged).connect == ("tcp/127.0.0.1:7009",)
