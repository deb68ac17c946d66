"""A zendock service's parameters as its ROS 2 node's (``ros2 param list|get|set|describe``).

Each face node is created without rclpy's own parameter services; this serves the six
``rcl_interfaces`` services in their place, relayed to the zendock node's ``_param/list|get|set``
(:mod:`shared.parameter_server`), so ROS 2 sees what zendock holds: its parameters with their types,
``use_sim_time`` as the service runs, a read-only parameter refused with zendock's reason. Values convert
through :mod:`shared.ros2.parameter_values`. zendock sets one parameter at a time, so an atomic set of
more than one is refused. Imported only in ``.venv-ros2`` (rclpy).
"""

from __future__ import annotations

import json
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

from shared.interfaces.parameters import (
    LIST_PARAMETERS,
    SET_PARAMETER,
    ListParametersRequest,
    SetParameterRequest,
)
from shared.interfaces.parameters import ParameterDescriptor as ZendockDescriptor
from shared.names import parameter_service, topic_key
from shared.node import Node, ServiceError, call_service
from shared.ros2 import parameter_values

#: How long a ROS 2 parameter request waits for the zendock node.
PARAMETER_WAIT_S = 5.0


def ros_value(value: Any) -> Any:
    type_code, field_value = parameter_values.to_ros(value)
    msg = ParameterValue(type=type_code)
    if type_code != parameter_values.NOT_SET:
        setattr(msg, parameter_values.FIELD_OF[type_code], field_value)
    return msg


class ParameterRelay:
    """The parameter services of one face node, answering from zendock's node ``owner``."""

    def __init__(self, zendock: Node, rnode: Any, owner: str, callback_group: Any) -> None:
        self._zendock = zendock
        self._owner = owner
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

    def _key(self, verb: str) -> str:
        return topic_key(self._zendock.namespace, parameter_service(self._owner, verb))

    def _zendock_parameters(self) -> dict[str, ZendockDescriptor]:
        """Every parameter of the zendock node, by name (empty when it does not answer: ROS 2 sees none)."""
        try:
            reply = call_service(
                self._zendock.session,
                self._key("list"),
                LIST_PARAMETERS,
                ListParametersRequest(),
                PARAMETER_WAIT_S,
            )
        except ServiceError:
            return {}
        return {p.name: p for p in reply.parameters}

    def _list(self, request: Any, response: Any) -> Any:
        names = sorted(self._zendock_parameters())
        prefixes = [p.rstrip(".") for p in request.prefixes]
        if prefixes:
            names = [n for n in names if any(n == p or n.startswith(p + ".") for p in prefixes)]
        response.result = ListParametersResult(
            names=names, prefixes=sorted({n.rsplit(".", 1)[0] for n in names if "." in n})
        )
        return response

    def _get(self, request: Any, response: Any) -> Any:
        known = self._zendock_parameters()
        response.values = [
            ros_value(json.loads(known[name].value_json)) if name in known else ParameterValue()
            for name in request.names
        ]
        return response

    def _types(self, request: Any, response: Any) -> Any:
        known = self._zendock_parameters()
        response.types = [
            parameter_values.to_ros(json.loads(known[name].value_json))[0] if name in known else 0
            for name in request.names
        ]
        return response

    def _describe(self, request: Any, response: Any) -> Any:
        known = self._zendock_parameters()
        descriptors = []
        for name in request.names:
            p = known.get(name)
            if p is None:
                descriptors.append(ParameterDescriptor(name=name))
                continue
            descriptors.append(
                ParameterDescriptor(
                    name=name,
                    type=parameter_values.to_ros(json.loads(p.value_json))[0],
                    description=p.description,
                    additional_constraints=f"set while running: applies {p.applies}" if p.settable else "",
                    read_only=not p.settable,
                )
            )
        response.descriptors = descriptors
        return response

    def _set_one(self, parameter: Any, known: dict[str, ZendockDescriptor]) -> Any:
        current = known.get(parameter.name)
        if current is None:
            return SetParametersResult(successful=False, reason=f"{parameter.name}: no such parameter")
        value = parameter.value
        try:
            field = parameter_values.FIELD_OF.get(value.type)
            wanted = parameter_values.from_ros(
                value.type, getattr(value, field) if field else None, json.loads(current.value_json)
            )
        except ValueError as exc:
            return SetParametersResult(successful=False, reason=f"{parameter.name}: {exc}")
        request = SetParameterRequest(name=parameter.name, value_json=json.dumps(wanted))
        try:
            reply = call_service(
                self._zendock.session, self._key("set"), SET_PARAMETER, request, PARAMETER_WAIT_S
            )
        except ServiceError as exc:
            return SetParametersResult(successful=False, reason=f"{parameter.name}: {exc}")
        return SetParametersResult(successful=reply.successful, reason=reply.reason)

    def _set(self, request: Any, response: Any) -> Any:
        known = self._zendock_parameters()
        response.results = [self._set_one(p, known) for p in request.parameters]
        return response

    def _set_atomically(self, request: Any, response: Any) -> Any:
        if len(request.parameters) != 1:
            response.result = SetParametersResult(
                successful=False, reason="zendock sets one parameter at a time: use set_parameters"
            )
            return response
        response.result = self._set_one(request.parameters[0], self._zendock_parameters())
        return response
