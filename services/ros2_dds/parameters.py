"""A zendock service's parameters as its ROS 2 node's (``ros2 param list|get|set|describe``).

Each face node is created without rclpy's own parameter services; this serves the six
``rcl_interfaces`` services in their place, relayed to the zendock node's ``_param/list|get|set``
(:mod:`shared.parameter_server`). What they answer is decided in :mod:`shared.ros2.parameter_answers`,
the same as on the rmw_zenoh face; this module makes rclpy's messages of it. Imported only in
``.venv-ros2`` (rclpy).
"""

from __future__ import annotations

from typing import Any

from rcl_interfaces.msg import (
    ListParametersResult,
    ParameterDescriptor,
    ParameterValue,
    SetParametersResult,
)
from rcl_interfaces.srv import (
    DescribeParameters,
    GetParameters,
    GetParameterTypes,
    ListParameters,
    SetParameters,
    SetParametersAtomically,
)

from shared.node import Node
from shared.ros2 import parameter_values
from shared.ros2.parameter_answers import SetOutcome, Value, answers_from_bus


def ros_value(value: Value) -> Any:
    msg = ParameterValue(type=value.type)
    if value.field is not None:
        setattr(msg, value.field, value.field_value)
    return msg


def _value(msg: Any) -> Value:
    """A ROS 2 ParameterValue as the answers take it (rclpy's arrays read as lists where they are set)."""
    field = parameter_values.FIELD_OF.get(msg.type)
    return Value(msg.type, getattr(msg, field) if field else None)


def _result(outcome: SetOutcome) -> Any:
    return SetParametersResult(successful=outcome[0], reason=outcome[1])


class ParameterRelay:
    """The parameter services of one face node, answering from zendock's node ``owner``."""

    def __init__(self, zendock: Node, rnode: Any, owner: str, callback_group: Any) -> None:
        self._answers = answers_from_bus(zendock.session, zendock.namespace, owner)
        self.services = [
            rnode.create_service(srv, f"~/{name}", handler, callback_group=callback_group)
            for srv, name, handler in (
                (ListParameters, "list_parameters", self._list),
                (GetParameters, "get_parameters", self._get),
                (SetParameters, "set_parameters", self._set),
                (SetParametersAtomically, "set_parameters_atomically", self._set_atomically),
                (DescribeParameters, "describe_parameters", self._describe),
                (GetParameterTypes, "get_parameter_types", self._types),
            )
        ]

    def _list(self, request: Any, response: Any) -> Any:
        names, prefixes = self._answers.names(list(request.prefixes))
        response.result = ListParametersResult(names=names, prefixes=prefixes)
        return response

    def _get(self, request: Any, response: Any) -> Any:
        response.values = [ros_value(v) for v in self._answers.values(list(request.names))]
        return response

    def _types(self, request: Any, response: Any) -> Any:
        response.types = self._answers.types(list(request.names))
        return response

    def _describe(self, request: Any, response: Any) -> Any:
        response.descriptors = [
            ParameterDescriptor(
                name=d.name,
                type=d.type,
                description=d.description,
                additional_constraints=d.additional_constraints,
                read_only=d.read_only,
            )
            for d in self._answers.describe(list(request.names))
        ]
        return response

    def _set(self, request: Any, response: Any) -> Any:
        wanted = [(p.name, _value(p.value)) for p in request.parameters]
        response.results = [_result(o) for o in self._answers.set_each(wanted)]
        return response

    def _set_atomically(self, request: Any, response: Any) -> Any:
        wanted = [(p.name, _value(p.value)) for p in request.parameters]
        response.result = _result(self._answers.set_atomically(wanted))
        return response
