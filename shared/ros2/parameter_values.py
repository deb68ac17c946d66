"""zendock's parameter values as ROS 2's ``rcl_interfaces/ParameterValue``, and back.

zendock's parameters travel as JSON (``zendock_msgs/srv/GetParameter``'s ``value_json``); ROS 2's carry a
type code and one field per type. Scalars and flat lists of one kind map one to one. What ROS 2 cannot
type (a list of lists, a mapping, a mixed or an empty list) goes as a STRING holding its JSON, and is
read back from JSON when set. Pure: the DDS face builds rclpy's messages from these tuples.
"""

from __future__ import annotations

import json
from typing import Any

NOT_SET, BOOL, INTEGER, DOUBLE, STRING = 0, 1, 2, 3, 4
BOOL_ARRAY, INTEGER_ARRAY, DOUBLE_ARRAY, STRING_ARRAY = 6, 7, 8, 9

#: The ParameterValue field each type code fills.
FIELD_OF = {
    BOOL: "bool_value",
    INTEGER: "integer_value",
    DOUBLE: "double_value",
    STRING: "string_value",
    BOOL_ARRAY: "bool_array_value",
    INTEGER_ARRAY: "integer_array_value",
    DOUBLE_ARRAY: "double_array_value",
    STRING_ARRAY: "string_array_value",
}


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def to_ros(value: Any) -> tuple[int, Any]:
    """``(type code, the value for its field)`` of a zendock parameter's value."""
    if value is None:
        return NOT_SET, None
    if isinstance(value, bool):
        return BOOL, value
    if _is_int(value):
        return INTEGER, value
    if isinstance(value, float):
        return DOUBLE, value
    if isinstance(value, str):
        return STRING, value
    if isinstance(value, list | tuple) and value:
        items = list(value)
        if all(isinstance(v, bool) for v in items):
            return BOOL_ARRAY, items
        if all(_is_int(v) for v in items):
            return INTEGER_ARRAY, items
        if all(_is_int(v) or isinstance(v, float) for v in items):
            return DOUBLE_ARRAY, [float(v) for v in items]
        if all(isinstance(v, str) for v in items):
            return STRING_ARRAY, items
    return STRING, json.dumps(value)


def from_ros(type_code: int, field_value: Any, current: Any) -> Any:
    """The value to set, from a ROS 2 ParameterValue's type and field, for a parameter now ``current``
    (a STRING for a parameter ROS 2 sees as JSON text is read back as JSON). ValueError names a type ROS 2
    sent that zendock cannot take."""
    if type_code == STRING and not isinstance(current, str) and to_ros(current)[0] == STRING:
        try:
            return json.loads(field_value)
        except ValueError:
            raise ValueError(f"expected JSON text like {json.dumps(current)}, got {field_value!r}") from None
    if type_code in (BOOL, INTEGER, DOUBLE, STRING):
        return field_value
    if type_code in (BOOL_ARRAY, INTEGER_ARRAY, DOUBLE_ARRAY, STRING_ARRAY):
        return list(field_value)
    raise ValueError(f"parameter type {type_code} is not one zendock takes (not set, or a byte array)")
