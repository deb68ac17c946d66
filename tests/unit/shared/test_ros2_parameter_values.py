"""zendock's parameter values as ROS 2's ParameterValue type codes and fields, and back."""

from __future__ import annotations

import pytest

from shared.ros2 import parameter_values as pv


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        (True, (pv.BOOL, True)),
        (3, (pv.INTEGER, 3)),
        (0.25, (pv.DOUBLE, 0.25)),
        ("home", (pv.STRING, "home")),
        ([1.0, 2, 3.5], (pv.DOUBLE_ARRAY, [1.0, 2.0, 3.5])),
        ([1, 2], (pv.INTEGER_ARRAY, [1, 2])),
        (["r1", "r2"], (pv.STRING_ARRAY, ["r1", "r2"])),
        ([True, False], (pv.BOOL_ARRAY, [True, False])),
        (None, (pv.NOT_SET, None)),
        ([[0.0, 1.0, 0.0]], (pv.STRING, "[[0.0, 1.0, 0.0]]")),  # ROS 2 cannot type it: JSON text
        ([], (pv.STRING, "[]")),
        ({"x": 1}, (pv.STRING, '{"x": 1}')),
    ],
)
def test_values_get_the_type_ros2_would_give_them(value: object, expected: tuple[int, object]) -> None:
    assert pv.to_ros(value) == expected


def test_a_value_set_from_ros2_comes_back_as_zendock_holds_it() -> None:
    assert pv.from_ros(pv.BOOL, False, True) is False
    assert pv.from_ros(pv.INTEGER, 5, 1.0) == 5  # zendock's model turns it into 5.0
    assert pv.from_ros(pv.STRING, "[[1, 2, 0]]", [[0.0, 1.0, 0.0]]) == [[1, 2, 0]]
    assert pv.from_ros(pv.STRING, "home", "dock") == "home"
    assert pv.from_ros(pv.DOUBLE_ARRAY, (1.0, 2.0), [0.0]) == [1.0, 2.0]
    with pytest.raises(ValueError, match="expected JSON text"):
        pv.from_ros(pv.STRING, "not json", [[0.0]])
    with pytest.raises(ValueError, match="not one zendock takes"):
        pv.from_ros(pv.NOT_SET, None, 1)
