"""Endpoints, namespace and key resolution for the keys verbs."""

from __future__ import annotations

import pytest

from deploy.keys.connection import bus_options, has_wildcards, resolve_endpoints, resolve_key, session_spec
from deploy.keys.errors import EXIT_USAGE, KeysError
from shared.session import DEFAULT_ROUTER_ENDPOINT


def test_connect_flags_win_over_environment() -> None:
    env = {"ZENDOCK_CONNECT": "tcp/10.0.0.1:7447", "ZENOH_CONNECT": "tcp/10.0.0.2:7447"}
    assert resolve_endpoints(["tcp/1.2.3.4:7447"], env) == ("tcp/1.2.3.4:7447",)


def test_zendock_connect_wins_over_zenoh_connect_and_splits_on_commas() -> None:
    env = {"ZENDOCK_CONNECT": "tcp/10.0.0.1:7447, tcp/10.0.0.3:7447", "ZENOH_CONNECT": "tcp/10.0.0.2:7447"}
    assert resolve_endpoints(None, env) == ("tcp/10.0.0.1:7447", "tcp/10.0.0.3:7447")
    assert resolve_endpoints(None, {"ZENOH_CONNECT": "tcp/10.0.0.2:7447"}) == ("tcp/10.0.0.2:7447",)


def test_default_endpoint_without_flags_or_environment() -> None:
    assert resolve_endpoints(None, {}) == (DEFAULT_ROUTER_ENDPOINT,)
    assert resolve_endpoints([], {"ZENDOCK_CONNECT": " , "}) == (DEFAULT_ROUTER_ENDPOINT,)


def test_namespace_from_flag_or_environment_and_normalised() -> None:
    assert bus_options(None, "/robot1/", environ={}).namespace == "robot1"
    assert bus_options(None, None, environ={"ZENDOCK_NAMESPACE": "robot2"}).namespace == "robot2"
    assert bus_options(None, "", environ={"ZENDOCK_NAMESPACE": "robot2"}).namespace == ""


def test_bad_namespace_and_timeout_are_usage_errors() -> None:
    with pytest.raises(KeysError) as bad_ns:
        bus_options(None, "robot*", environ={})
    assert bad_ns.value.exit_code == EXIT_USAGE and "--namespace" in str(bad_ns.value)
    with pytest.raises(KeysError) as bad_timeout:
        bus_options(None, "", connect_timeout_s=0, environ={})
    assert bad_timeout.value.exit_code == EXIT_USAGE


@pytest.mark.parametrize(
    ("namespace", "typed", "expected"),
    [
        ("robot1", "cmd_vel", "robot1/cmd_vel"),
        ("robot1", "/cmd_vel", "robot1/cmd_vel"),  # a leading slash is the namespace root, not the bus root
        ("", "/cmd_vel", "cmd_vel"),
        ("a/b", "simulator/teleport/", "a/b/simulator/teleport"),
        ("robot1", "**", "robot1/**"),
    ],
)
def test_keys_are_relative_to_the_namespace(namespace: str, typed: str, expected: str) -> None:
    assert resolve_key(namespace, typed) == expected


@pytest.mark.parametrize("typed", ["", "/", "a//b", "a/b*c"])
def test_invalid_keys_are_usage_errors(typed: str) -> None:
    with pytest.raises(KeysError) as error:
        resolve_key("robot1", typed)
    assert error.value.exit_code == EXIT_USAGE


def test_wildcards_can_be_refused() -> None:
    assert has_wildcards("robot1/**") and has_wildcards("a/*/c") and not has_wildcards("robot1/cmd_vel")
    with pytest.raises(KeysError, match="wildcards"):
        resolve_key("robot1", "*", allow_wildcards=False)


def test_session_fails_fast_instead_of_retrying_for_ever() -> None:
    spec = session_spec(bus_options(["tcp/127.0.0.1:1"], "", connect_timeout_s=1.5, environ={}))
    overrides = dict(spec.overrides)
    assert spec.mode == "client" and spec.connect == ("tcp/127.0.0.1:1",)
    assert overrides == {"connect/timeout_ms": "1500", "connect/exit_on_failure": "true"}
