"""The launcher's public surface is what its docstring promises."""

from __future__ import annotations

import socket

import deploy.launcher as launcher
from deploy.launcher import ServiceStatus, free_endpoint, is_ready


def test_exported_names() -> None:
    assert set(launcher.__all__) == {
        "Backoff",
        "Launcher",
        "RestartPolicy",
        "ServiceStatus",
        "Stack",
        "StackNotReady",
        "free_endpoint",
        "free_tcp_port",
        "is_ready",
        "load_stack",
    }
    assert all(hasattr(launcher, name) for name in launcher.__all__)


def test_free_endpoint_is_a_bindable_loopback_port() -> None:
    endpoint = free_endpoint()
    scheme, address = endpoint.split("/")
    host, port = address.rsplit(":", 1)
    assert (scheme, host) == ("tcp", "127.0.0.1")
    with socket.socket() as probe:
        probe.bind((host, int(port)))


def test_ps_json_has_exactly_the_promised_keys() -> None:
    status = ServiceStatus(
        "planner",
        "running",
        42,
        1,
        "healthy",
        phase="running",
        detail="up 3s",
        starts=2,
        exit_code=-9,
        started_at=1_795_000_000.25,
    )
    assert status.ps_json() == {
        "name": "planner",
        "state": "running",
        "pid": 42,
        "restarts": 1,
        "health": "healthy",
        "exit_code": -9,
        "started_at": "2026-11-18T11:06:40.250+00:00",
        "members": [],
        "namespace": "",
    }
    group = ServiceStatus("robot", "running", 43, 0, "healthy", members=["battery", "pose"])
    assert group.ps_json()["members"] == ["battery", "pose"]
    assert ServiceStatus.from_dict(group.to_dict()) == group
    never = ServiceStatus("docking", "stopped", None, 0, "none")
    assert never.ps_json()["exit_code"] is None and never.ps_json()["started_at"] is None
    assert ServiceStatus.from_dict({**status.to_dict(), "unknown": 1}) == status


def test_ps_groups_a_fleets_services_by_robot() -> None:
    from deploy.commands.ps import format_table

    statuses = [
        ServiceStatus("planner_r2", "running", 5, 0, "healthy", namespace="r2"),
        ServiceStatus("simulator", "running", 1, 0, "healthy"),
        ServiceStatus("battery_r1", "running", 2, 0, "healthy", namespace="r1"),
        ServiceStatus("planner_r1", "running", 3, 0, "healthy", namespace="r1"),
    ]
    lines = format_table(statuses).splitlines()
    names = [line.split()[0] for line in lines]
    assert names == ["NAME", "simulator", "r1/", "battery_r1", "planner_r1", "r2/", "planner_r2"], lines
    alone = format_table([ServiceStatus("docking", "running", 7, 0, "healthy")]).splitlines()
    assert [line.split()[0] for line in alone] == ["NAME", "docking"], "one namespace: no groups"


def test_ps_shows_a_step_that_ran_to_its_end_as_done_and_a_crash_as_exited() -> None:
    from deploy.commands.ps import format_table

    done = ServiceStatus("map", "exited", None, 0, "none", phase="exited", exit_code=0)
    crashed = ServiceStatus("planner", "exited", None, 3, "none", phase="exited", exit_code=1)
    rows = [line.split()[:2] for line in format_table([done, crashed]).splitlines()[1:]]
    assert rows == [["map", "done"], ["planner", "exited"]]
    assert done.ps_json()["state"] == "exited" and done.ps_json()["exit_code"] == 0, (
        "JSON as Compose gives it"
    )


def test_readiness_counts_completed_steps_and_unchecked_services() -> None:
    assert is_ready(ServiceStatus("a", "running", 1, 0, "healthy"))
    assert is_ready(ServiceStatus("a", "running", 1, 0, "none"))
    assert not is_ready(ServiceStatus("a", "running", 1, 0, "starting"))
    assert not is_ready(ServiceStatus("a", "running", 1, 0, "unhealthy"))
    assert is_ready(ServiceStatus("map", "exited", None, 0, "none", phase="exited", exit_code=0))
    assert not is_ready(ServiceStatus("map", "exited", None, 0, "none", phase="exited", exit_code=1))
    assert not is_ready(ServiceStatus("a", "stopped", None, 0, "none", phase="waiting"))
