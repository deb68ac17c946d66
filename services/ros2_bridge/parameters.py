"""zendock services' parameters on rmw_zenoh: ``ros2 param list|get|set|describe`` on the bridge's nodes.

Each ROS 2 node the bridge shows for a zendock service serves ``rcl_interfaces``' six parameter services
(``/<node>/list_parameters``, ``get_parameters``, ``set_parameters``, ``set_parameters_atomically``,
``describe_parameters``, ``get_parameter_types``) as rmw_zenoh queryables. What they answer is decided in
:mod:`shared.ros2.parameter_answers`, the same as on the DDS face, from the zendock node's ``_param/list``
and ``_param/set``. Requests are answered on a worker thread of their own: a zendock call blocks, and
Zenoh's threads must not.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
import zenoh

from shared.node import Node
from shared.ros2 import interfaces, parameter_values
from shared.ros2 import types as ros_types
from shared.ros2.parameter_answers import ParameterAnswers, SetOutcome, Value, answers_from_bus
from shared.ros2.wire import Attachment, data_key

#: A numeric array field's dtype in rosbags' messages.
_ARRAY_DTYPES = {
    "bool_array_value": np.bool_,
    "integer_array_value": np.int64,
    "double_array_value": np.float64,
}


def _ros(type_name: str, **fields: Any) -> Any:
    """A rosbags message of ``type_name`` with ``fields`` set and ROS 2's defaults for the rest."""
    return dataclasses.replace(ros_types.to_ros(None, type_name), **fields)


def ros_value(value: Value) -> Any:
    field = value.field
    if field is None:
        return _ros("rcl_interfaces/msg/ParameterValue", type=value.type)
    field_value = value.field_value
    if field in _ARRAY_DTYPES:
        field_value = np.asarray(field_value, dtype=_ARRAY_DTYPES[field])
    return _ros("rcl_interfaces/msg/ParameterValue", type=value.type, **{field: field_value})


def _value(ros_msg: Any) -> Value:
    """A ROS 2 ParameterValue as the answers take it (arrays as lists)."""
    field = parameter_values.FIELD_OF.get(ros_msg.type)
    field_value = getattr(ros_msg, field) if field else None
    if isinstance(field_value, np.ndarray):
        field_value = field_value.tolist()
    return Value(int(ros_msg.type), field_value)


def _result(outcome: SetOutcome) -> Any:
    return _ros("rcl_interfaces/msg/SetParametersResult", successful=outcome[0], reason=outcome[1])


def answer(answers: ParameterAnswers, verb: str, request: Any) -> Any:
    """The response to ``request`` of the parameter service ``verb`` (``get_parameters``, ...)."""
    response_type = interfaces.service_parts(interfaces.PARAMETER_SERVICES[verb][0])[1]
    if verb == "list_parameters":
        names, prefixes = answers.names(list(request.prefixes))
        result = _ros("rcl_interfaces/msg/ListParametersResult", names=names, prefixes=prefixes)
        return _ros(response_type, result=result)
    if verb == "get_parameters":
        return _ros(response_type, values=[ros_value(v) for v in answers.values(list(request.names))])
    if verb == "get_parameter_types":
        return _ros(response_type, types=np.asarray(answers.types(list(request.names)), dtype=np.uint8))
    if verb == "describe_parameters":
        descriptors = [
            _ros("rcl_interfaces/msg/ParameterDescriptor", **dataclasses.asdict(d))
            for d in answers.describe(list(request.names))
        ]
        return _ros(response_type, descriptors=descriptors)
    wanted = [(p.name, _value(p.value)) for p in request.parameters]
    if verb == "set_parameters":
        return _ros(response_type, results=[_result(o) for o in answers.set_each(wanted)])
    if verb == "set_parameters_atomically":
        return _ros(response_type, result=_result(answers.set_atomically(wanted)))
    raise ValueError(f"no parameter service {verb!r}")


class ParameterRelay:
    """The six parameter services of each bridged node, answered from its zendock service's parameters."""

    def __init__(
        self,
        node: Node,
        domain_id: int,
        refuse: Callable[..., None],
        count: Callable[[str], None],
    ) -> None:
        self._node = node
        self._domain_id = domain_id
        self._refuse = refuse
        self._count = count
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="ros2-parameters")
        self._queryables: list[Any] = []

    def serve(self, owner: str, verb: str, ros_name: str) -> None:
        """Answer ROS 2's ``ros_name`` (``/<node>/<verb>``, fully qualified) for zendock's ``owner``."""
        ros_type = interfaces.PARAMETER_SERVICES[verb][0]
        key = data_key(self._domain_id, ros_name, ros_type, ros_types.type_hash(ros_type))
        answers = answers_from_bus(self._node.session, self._node.namespace, owner)

        def on_query(query: zenoh.Query) -> None:
            payload = query.payload.to_bytes() if query.payload is not None else b""
            attachment = query.attachment.to_bytes() if query.attachment is not None else b""
            self._pool.submit(self._answer, answers, verb, ros_name, query, payload, attachment)

        self._queryables.append(self._node.session.declare_queryable(key, on_query, complete=True))

    def _answer(
        self,
        answers: ParameterAnswers,
        verb: str,
        where: str,
        query: zenoh.Query,
        payload: bytes,
        attachment: bytes,
    ) -> None:
        try:
            try:
                caller = Attachment.decode(attachment)
                request_type, response_type = interfaces.service_parts(interfaces.PARAMETER_SERVICES[verb][0])
                request = ros_types.from_cdr(payload, request_type)
            except ValueError as exc:  # Ros2TypeError is one
                self._refuse(f"parameters-request-{verb}", "%s: %s", where, exc)
                query.reply_err(f"{where}: {exc}".encode())
                return
            self._count(f"parameters {where}")
            reply = bytes(ros_types.typestore().serialize_cdr(answer(answers, verb, request), response_type))
            query.reply(
                query.key_expr,
                reply,
                attachment=Attachment(caller.sequence_number, time.time_ns(), caller.gid).encode(),
            )
        except Exception as exc:  # a bug here must not end the worker: answer, log, go on
            self._refuse(f"parameters-error-{verb}", "%s: %s: %s", where, type(exc).__name__, exc)
            query.reply_err(f"{where}: internal error".encode())
        finally:
            query.drop()

    def close(self) -> None:
        for queryable in self._queryables:
            queryable.undeclare()
        self._pool.shutdown(wait=False, cancel_futures=True)
