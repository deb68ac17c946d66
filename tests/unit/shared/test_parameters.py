"""Runtime parameters without a bus: what may change, validation as at start-up, listeners, the server's answers."""

from __future__ import annotations

import json
import logging
from typing import Annotated, Any

import msgspec
import pytest
from msgspec import Meta

from shared import structs
from shared.interfaces.parameters import GetParameterRequest, ListParametersRequest, SetParameterRequest
from shared.parameter_server import ParameterServer, attach_parameters
from shared.parameters import AT_ONCE, ParameterRefused, ParameterTable, ServiceParams, runtime_settable
from tests.support.processes import REPO_ROOT


class Lidar(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    noise_m: Annotated[float, Meta(ge=0.0, extra=runtime_settable())] = 0.01
    rate_hz: Annotated[float, Meta(gt=0.0)] = 10.0


class DemoParams(ServiceParams):
    speed_mps: Annotated[
        float, Meta(gt=0.0, le=1.0, description="top speed", extra=runtime_settable("next run"))
    ] = 0.5
    min_speed_mps: Annotated[float, Meta(gt=0.0, extra=runtime_settable())] = 0.1
    frame_id: Annotated[str, Meta(description="read at start")] = "base_link"
    mount: tuple[float, float, float] = (0.1, 0.0, 0.0)
    lidar: Lidar = msgspec.field(default_factory=Lidar)

    def __post_init__(self) -> None:
        if self.min_speed_mps > self.speed_mps:
            raise ValueError(
                f"min_speed_mps ({self.min_speed_mps}) must not exceed speed_mps ({self.speed_mps})"
            )


def test_list_shows_every_parameter_flattened_with_value_and_settable() -> None:
    table = ParameterTable(DemoParams())
    rows = {info.name: info for info in table.describe()}
    assert list(rows) == sorted(rows)
    assert set(rows) == {
        "use_sim_time",
        "speed_mps",
        "min_speed_mps",
        "frame_id",
        "mount",
        "lidar.noise_m",
        "lidar.rate_hz",
    }
    assert (rows["speed_mps"].value, rows["speed_mps"].settable, rows["speed_mps"].applies) == (
        0.5,
        True,
        "next run",
    )
    assert rows["speed_mps"].description == "top speed"
    assert (rows["frame_id"].settable, rows["frame_id"].applies) == (False, "")
    assert rows["mount"].value == [0.1, 0.0, 0.0] and rows["mount"].value_json == "[0.1, 0.0, 0.0]"
    assert rows["lidar.noise_m"].settable and rows["lidar.noise_m"].applies == AT_ONCE
    assert table.settable_names() == ["lidar.noise_m", "min_speed_mps", "speed_mps"]


def test_a_good_value_is_written_into_the_live_model() -> None:
    params = DemoParams()
    table = ParameterTable(params)
    info = table.set("speed_mps", "0.8")  # coerced as at start-up (-p speed_mps=0.8 would give a float)
    assert info.value == 0.8 and params.speed_mps == 0.8 and table.get("speed_mps").value == 0.8
    table.set("lidar.noise_m", 0.05)
    assert params.lidar.noise_m == 0.05


@pytest.mark.parametrize(
    ("name", "value", "reason"),
    [
        ("speed_mps", 2.0, "speed_mps: must be at most 1.0 (got 2.0)"),
        ("speed_mps", "fast", "speed_mps: expected float, got text (got 'fast')"),
        ("speed_mps", 0.05, "speed_mps: min_speed_mps (0.1) must not exceed speed_mps (0.05) (got 0.05)"),
        ("lidar.noise_m", -1, "lidar.noise_m: must be at least 0.0 (got -1)"),
        (
            "frame_id",
            "odom",
            "frame_id: read at start-up only, cannot change while running (settable: lidar.noise_m, "
            "min_speed_mps, speed_mps)",
        ),
        ("lidar.rate_hz", 5.0, "lidar.rate_hz: read at start-up only"),
        (
            "speed",
            0.3,
            "speed: no such parameter (did you mean speed_mps?) (settable: lidar.noise_m, min_speed_mps, speed_mps)",
        ),
    ],
)
def test_a_refused_change_names_the_reason_and_changes_nothing(name: str, value: Any, reason: str) -> None:
    params = DemoParams()
    before = structs.plain(params)
    with pytest.raises(ParameterRefused) as refused:
        ParameterTable(params).set(name, value)
    assert str(refused.value).startswith(reason)
    assert structs.plain(params) == before


def test_get_of_an_unknown_name_is_refused() -> None:
    with pytest.raises(ParameterRefused, match="nope: no such parameter"):
        ParameterTable(DemoParams()).get("nope")


def test_listeners_hear_accepted_changes_and_may_refuse_them() -> None:
    params = DemoParams()
    table = ParameterTable(params)
    heard: list[tuple[str, Any]] = []
    table.on_set(["speed_mps", "min_speed_mps"], lambda name, value: heard.append((name, value)))
    table.set("speed_mps", 0.7)
    table.set("lidar.noise_m", 0.02)  # not registered
    assert heard == [("speed_mps", 0.7)]

    def refuse(name: str, value: Any) -> None:
        raise ValueError("the motors are hot")

    table.on_set("min_speed_mps", refuse)
    with pytest.raises(ParameterRefused, match="min_speed_mps: the motors are hot"):
        table.set("min_speed_mps", 0.2)
    assert params.min_speed_mps == 0.1  # undone


def test_a_listener_only_for_settable_names() -> None:
    with pytest.raises(ValueError, match="frame_id"):
        ParameterTable(DemoParams()).on_set("frame_id", lambda *_: None)


def test_services_mark_what_may_change_while_running() -> None:
    from services.battery.node import Params as BatteryParams
    from services.docking.params import Params as DockingParams
    from services.planner.params import Params as PlannerParams

    assert ParameterTable(BatteryParams()).settable_names() == ["charge_scale", "drain_scale", "frozen"]
    assert {"max_linear_vel_mps", "max_angular_vel_radps", "inflation_radius_m"} <= set(
        ParameterTable(PlannerParams()).settable_names()
    )
    seed_room = str(REPO_ROOT / "deploy/worlds/seed_room.yaml")
    docking = set(ParameterTable(DockingParams(dock_database=seed_room)).settable_names())
    assert {"max_approach_speed_mps", "undock_speed_mps", "auto_dock"} <= docking
    assert "dock_database" not in docking and "controller" not in docking


class _FakeNode:
    """Just what ParameterServer needs of a node: a name, a log and create_service."""

    name = "demo"
    log = logging.getLogger("demo")

    def __init__(self) -> None:
        self.services: list[str] = []

    def create_service(self, srv: Any, name: str, handler: Any) -> Any:
        self.services.append(name)
        return None


class _Listening:
    def __init__(self) -> None:
        self.heard: list[tuple[str, Any]] = []

    def on_parameter_set(self, name: str, value: Any) -> None:
        self.heard.append((name, value))


def test_the_server_answers_list_get_and_set() -> None:
    node, service = _FakeNode(), _Listening()
    server: ParameterServer = attach_parameters(node, DemoParams(), service)  # type: ignore[arg-type]
    assert node.services == ["demo/_param/list", "demo/_param/get", "demo/_param/set"]
    listed = server._on_list(ListParametersRequest()).parameters
    assert [p.name for p in listed][:2] == ["frame_id", "lidar.noise_m"]
    assert server._on_get(GetParameterRequest(name="speed_mps")).parameter.value_json == "0.5"
    ok = server._on_set(SetParameterRequest(name="speed_mps", value_json=json.dumps(0.9)))
    assert ok.successful and ok.parameter.value_json == "0.9" and ok.parameter.applies == "next run"
    assert service.heard == [("speed_mps", 0.9)]
    bad = server._on_set(SetParameterRequest(name="speed_mps", value_json="-1"))
    assert not bad.successful and bad.reason == "speed_mps: must be greater than 0.0 (got -1)"
    not_json = server._on_set(SetParameterRequest(name="speed_mps", value_json="{"))
    assert not not_json.successful and "not JSON" in not_json.reason
    with pytest.raises(ParameterRefused):
        server._on_get(GetParameterRequest(name="nope"))


@pytest.mark.parametrize("value", [float("inf"), "Infinity", 1e999])
def test_an_infinite_value_is_refused(value: Any) -> None:
    params = DemoParams()
    with pytest.raises(ParameterRefused, match="lidar.noise_m: must be a finite number"):
        ParameterTable(params).set("lidar.noise_m", value)
    assert params.lidar.noise_m == 0.01


def test_a_listener_that_fails_leaves_the_old_value_in_force() -> None:
    params = DemoParams()
    table = ParameterTable(params)

    def broken(name: str, value: Any) -> None:
        raise RuntimeError("a bug in the service")

    table.on_set("speed_mps", broken)
    with pytest.raises(RuntimeError):
        table.set("speed_mps", 0.7)
    assert params.speed_mps == 0.5
