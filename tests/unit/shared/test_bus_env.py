"""One reading of where the bus is: flags, then ZENDOCK_CONNECT, then ZENOH_CONNECT (and ZENOH_LISTEN), each
from the environment, else from ./.env."""

from __future__ import annotations

from pathlib import Path

import pytest

from deploy.keys.connection import resolve_endpoints
from shared.bus_env import connect_from_env, listen_from_env
from shared.config_errors import ConfigError
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


@pytest.fixture
def in_a_project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A working directory with no bus variable in the environment."""
    for name in ("ZENDOCK_CONNECT", "ZENOH_CONNECT", "ZENOH_LISTEN"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_dotenv_moves_the_router_a_service_and_a_cli_command(in_a_project: Path) -> None:
    (in_a_project / ".env").write_text(
        "# as zendock up reads it\nexport ZENOH_LISTEN=tcp/127.0.0.1:7623\nZENOH_CONNECT='tcp/127.0.0.1:7623'\n"
    )
    assert listen_from_env() == ("tcp/127.0.0.1:7623",)
    assert options_from_args(build_arg_parser("viz").parse_args([])).connect == ("tcp/127.0.0.1:7623",)
    assert resolve_endpoints(None) == ("tcp/127.0.0.1:7623",)


def test_the_environment_wins_over_dotenv(in_a_project: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (in_a_project / ".env").write_text("ZENOH_CONNECT=tcp/127.0.0.1:7623\n")
    monkeypatch.setenv("ZENOH_CONNECT", "tcp/127.0.0.1:7002")
    assert connect_from_env() == ("tcp/127.0.0.1:7002",)
    monkeypatch.delenv("ZENOH_CONNECT")
    monkeypatch.setenv("ZENDOCK_CONNECT", "tcp/127.0.0.1:7001")  # the first variable that is set holds
    assert connect_from_env() == ("tcp/127.0.0.1:7001",)


def test_a_malformed_dotenv_is_named_not_passed_over(in_a_project: Path) -> None:
    (in_a_project / ".env").write_text("ZENOH_CONNECT=tcp/127.0.0.1:7623\nthis is not a variable\n")
    with pytest.raises(ConfigError, match=r"\.env:2: expected KEY=VALUE"):
        connect_from_env()
