"""``zendock container``'s command line: services split at '+', loaded by name, one session for all."""

from __future__ import annotations

import argparse

import pytest

from deploy.commands.container import load_spec, members_from, split_members
from shared.config_errors import ConfigError


def _args(
    *services: str, namespace: str | None = "r0", connect: list[str] | None = None
) -> argparse.Namespace:
    return argparse.Namespace(
        services=list(services), namespace=namespace, connect=connect, zenoh_config=None, log_level=None
    )


def test_services_split_at_plus_signs() -> None:
    assert split_members(["battery", "-p", "a=1", "+", "pose"]) == [["battery", "-p", "a=1"], ["pose"]]
    for bad in (["+", "pose"], ["battery", "+"], ["battery", "+", "+", "pose"]):
        with pytest.raises(ConfigError, match="separate two services"):
            split_members(bad)


def test_each_member_gets_its_own_parameters_and_the_groups_namespace() -> None:
    members = members_from(
        _args("battery", "-p", "use_sim_time=true", "+", "pose", "-p", "publish_rate_hz=5")
    )
    assert [m.options.node_name for m in members] == ["battery", "pose"]
    assert {m.options.namespace for m in members} == {"r0"}
    assert members[0].params.use_sim_time and not members[1].params.use_sim_time
    assert members[1].params.publish_rate_hz == 5  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("words", "message"),
    [
        (["nonsense"], "no service 'nonsense'"),
        (["../etc"], "not a service name"),
        (["battery", "-p", "no_such_parameter=1"], "no_such_parameter"),
        (["battery", "+", "battery"], "two services named 'battery'"),
        (["battery", "+", "pose", "--connect", "tcp/127.0.0.1:1"], "shares one session"),
        ([], "at least one service"),
    ],
)
def test_bad_groups_are_refused_by_name(words: list[str], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        members_from(_args(*words))


def test_every_service_can_run_in_a_container() -> None:
    for name in ("simulator", "battery", "pose", "planner", "docking", "perception", "viz", "ros2_bridge"):
        assert load_spec(name).name == name
