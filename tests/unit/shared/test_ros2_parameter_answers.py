"""What both ROS 2 faces answer to ``ros2 param``, from a zendock node's parameter list."""

from __future__ import annotations

import json

from shared.interfaces.parameters import ParameterDescriptor
from shared.ros2 import parameter_values as pv
from shared.ros2.parameter_answers import Descriptor, ParameterAnswers, Value

PARAMETERS = {
    "auto_dock": ParameterDescriptor("auto_dock", "true", True, "at once", "dock when the battery is low"),
    "use_sim_time": ParameterDescriptor("use_sim_time", "true", False, "", "follow the clock"),
    "staging.offset_m": ParameterDescriptor("staging.offset_m", "0.7", True, "next docking run", ""),
    "docks": ParameterDescriptor("docks", json.dumps([{"id": "home"}]), False, "", ""),
}


def _answers(stored: list[tuple[str, str]] | None = None) -> ParameterAnswers:
    def store(name: str, value_json: str) -> tuple[bool, str]:
        if stored is not None:
            stored.append((name, value_json))
        return True, ""

    return ParameterAnswers(lambda: dict(PARAMETERS), store)


def test_names_are_listed_with_their_groups_and_filtered_by_prefix() -> None:
    names, prefixes = _answers().names([])
    assert names == sorted(PARAMETERS) and prefixes == ["staging"]
    assert _answers().names(["staging."]) == (["staging.offset_m"], ["staging"])


def test_values_and_types_are_ros2s_and_an_unknown_name_is_not_set() -> None:
    got = _answers().values(["auto_dock", "staging.offset_m", "docks", "nope"])
    assert got[:2] == [Value(pv.BOOL, True), Value(pv.DOUBLE, 0.7)]
    assert got[2].type == pv.STRING and json.loads(got[2].field_value) == [{"id": "home"}]
    assert got[3] == Value(pv.NOT_SET)
    assert _answers().types(["auto_dock", "nope"]) == [pv.BOOL, pv.NOT_SET]


def test_a_parameter_read_at_start_up_is_described_read_only() -> None:
    sim_time, auto_dock = _answers().describe(["use_sim_time", "auto_dock"])
    assert sim_time == Descriptor("use_sim_time", pv.BOOL, "follow the clock", "", True)
    assert (
        not auto_dock.read_only and auto_dock.additional_constraints == "set while running: applies at once"
    )


def test_a_set_goes_to_zendock_as_json_and_an_untyped_value_or_unknown_name_is_refused_with_the_reason() -> (
    None
):
    stored: list[tuple[str, str]] = []
    answers = _answers(stored)
    assert answers.set_each([("auto_dock", Value(pv.BOOL, False))]) == [(True, "")]
    assert stored == [("auto_dock", "false")]
    wrong, missing = answers.set_each([("auto_dock", Value(pv.NOT_SET)), ("nope", Value(pv.BOOL, True))])
    assert not wrong[0] and wrong[1].startswith("auto_dock: parameter type 0 is not one zendock takes")
    assert missing == (False, "nope: no such parameter")
    assert answers.set_atomically([("auto_dock", Value(pv.BOOL, True))]) == (True, "")
    two = [("auto_dock", Value(pv.BOOL, True)), ("staging.offset_m", Value(pv.DOUBLE, 0.5))]
    assert answers.set_atomically(two) == (False, "zendock sets one parameter at a time: use set_parameters")
