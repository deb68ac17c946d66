"""The bridge's parameter answers as rmw_zenoh carries them: CDR of rcl_interfaces' services, both ways."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from services.ros2_bridge.parameters import answer
from shared.interfaces.parameters import ParameterDescriptor
from shared.ros2 import interfaces
from shared.ros2 import parameter_values as pv
from shared.ros2 import types as ros_types
from shared.ros2.parameter_answers import ParameterAnswers

PARAMETERS = {
    "auto_dock": ParameterDescriptor("auto_dock", "true", True, "at once", "dock when the battery is low"),
    "use_sim_time": ParameterDescriptor("use_sim_time", "true", False, "", ""),
    "docks": ParameterDescriptor("docks", json.dumps(["home", "spare"]), False, "", ""),
    "gains": ParameterDescriptor("gains", "[1.0, 2.5]", True, "at once", ""),
}


def _round_trip(verb: str, fields: dict[str, object], stored: list[tuple[str, str]]) -> object:
    """The request as CDR and back, answered, the response as CDR and back (what a peer reads)."""
    request_type, response_type = interfaces.service_parts(interfaces.PARAMETER_SERVICES[verb][0])
    store = ros_types.typestore()
    request = store.types[request_type](**fields)
    decoded = ros_types.from_cdr(bytes(store.serialize_cdr(request, request_type)), request_type)

    def keep(name: str, value_json: str) -> tuple[bool, str]:
        stored.append((name, value_json))
        return True, ""

    response = answer(ParameterAnswers(lambda: dict(PARAMETERS), keep), verb, decoded)
    return ros_types.from_cdr(bytes(store.serialize_cdr(response, response_type)), response_type)


def _parameter(name: str, **value: object) -> object:
    store = ros_types.typestore()
    base = ros_types.to_ros(None, "rcl_interfaces/msg/ParameterValue")
    return store.types["rcl_interfaces/msg/Parameter"](name=name, value=dataclasses.replace(base, **value))


def test_list_get_types_and_describe_come_back_as_ros2_reads_them() -> None:
    stored: list[tuple[str, str]] = []
    listed = _round_trip("list_parameters", {"prefixes": [], "depth": 0}, stored)
    assert listed.result.names == sorted(PARAMETERS)  # type: ignore[attr-defined]
    got = _round_trip("get_parameters", {"names": ["auto_dock", "docks", "gains", "nope"]}, stored)
    values = got.values  # type: ignore[attr-defined]
    assert (values[0].type, values[0].bool_value) == (pv.BOOL, True)
    assert (values[1].type, list(values[1].string_array_value)) == (pv.STRING_ARRAY, ["home", "spare"])
    assert (values[2].type, values[2].double_array_value.tolist()) == (pv.DOUBLE_ARRAY, [1.0, 2.5])
    assert values[3].type == pv.NOT_SET
    types = _round_trip("get_parameter_types", {"names": ["use_sim_time", "gains"]}, stored)
    assert types.types.tolist() == [pv.BOOL, pv.DOUBLE_ARRAY]  # type: ignore[attr-defined]
    described = _round_trip("describe_parameters", {"names": ["use_sim_time", "auto_dock"]}, stored)
    sim_time, auto_dock = described.descriptors  # type: ignore[attr-defined]
    assert sim_time.read_only and not auto_dock.read_only
    assert auto_dock.description == "dock when the battery is low"


def test_a_set_reaches_zendock_as_json_and_an_atomic_set_of_two_is_refused() -> None:
    stored: list[tuple[str, str]] = []
    one = _parameter("auto_dock", type=pv.BOOL, bool_value=False)
    gains = _parameter("gains", type=pv.DOUBLE_ARRAY, double_array_value=np.array([0.5, 0.25]))
    done = _round_trip("set_parameters", {"parameters": [one, gains]}, stored)
    assert [r.successful for r in done.results] == [True, True]  # type: ignore[attr-defined]
    assert stored == [("auto_dock", "false"), ("gains", "[0.5, 0.25]")]
    refused = _round_trip("set_parameters_atomically", {"parameters": [one, gains]}, stored)
    assert not refused.result.successful  # type: ignore[attr-defined]
    assert "one parameter at a time" in refused.result.reason  # type: ignore[attr-defined]


def test_an_unknown_service_is_refused() -> None:
    with pytest.raises(KeyError):
        answer(ParameterAnswers(dict, lambda _n, _v: (True, "")), "load_parameters", object())
