"""What ``rcl_interfaces``' six parameter services answer for a zendock node, whichever face asks.

Both ROS 2 faces show a zendock service's parameters as its ROS 2 node's (``ros2 param list|get|set|
describe``): the DDS face with rclpy's messages, the rmw_zenoh bridge with CDR it writes itself. What they
answer is the same and is decided here, from the zendock node's parameter list (``_param/list``,
:mod:`shared.parameter_server`) and its ``_param/set``: names and prefixes, values and types (through
:mod:`shared.ros2.parameter_values`), descriptors with a read-only parameter marked so, and sets, one at
a time (an atomic set of more than one is refused). A face turns these plain answers into its messages.
:class:`ParameterAnswers` takes the two zendock calls as functions (tests pass their own);
:func:`answers_from_bus` makes them blocking requests to the zendock node, from a face's own thread.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import zenoh

from shared.interfaces.parameters import (
    LIST_PARAMETERS,
    SET_PARAMETER,
    ListParametersRequest,
    SetParameterRequest,
)
from shared.interfaces.parameters import ParameterDescriptor as ZendockDescriptor
from shared.names import parameter_service, topic_key
from shared.node import ServiceError, call_service
from shared.ros2 import parameter_values

#: How long a ROS 2 parameter request waits for the zendock node (s).
PARAMETER_WAIT_S = 5.0

#: ``(successful, reason)`` of setting one parameter.
SetOutcome = tuple[bool, str]


@dataclass(frozen=True)
class Value:
    """A ParameterValue: its type code and the value of the field that type fills (None for NOT_SET)."""

    type: int
    field_value: Any = None

    @property
    def field(self) -> str | None:
        return parameter_values.FIELD_OF.get(self.type)


@dataclass(frozen=True)
class Descriptor:
    """A ParameterDescriptor's fields zendock fills."""

    name: str
    type: int = parameter_values.NOT_SET
    description: str = ""
    additional_constraints: str = ""
    read_only: bool = False


class ParameterAnswers:
    """Answers for one zendock node. ``fetch()`` lists its parameters by name (empty when it does not
    answer: ROS 2 then sees none); ``store(name, value_json)`` sets one and says how it went."""

    def __init__(
        self,
        fetch: Callable[[], dict[str, ZendockDescriptor]],
        store: Callable[[str, str], SetOutcome],
    ) -> None:
        self._fetch = fetch
        self._store = store

    def names(self, prefixes: list[str]) -> tuple[list[str], list[str]]:
        """``(names, prefixes)``: the parameters under any of ``prefixes`` (all without), and their groups."""
        names = sorted(self._fetch())
        wanted = [p.rstrip(".") for p in prefixes]
        if wanted:
            names = [n for n in names if any(n == p or n.startswith(p + ".") for p in wanted)]
        return names, sorted({n.rsplit(".", 1)[0] for n in names if "." in n})

    def values(self, names: list[str]) -> list[Value]:
        known = self._fetch()
        return [_value(known[name]) if name in known else Value(parameter_values.NOT_SET) for name in names]

    def types(self, names: list[str]) -> list[int]:
        return [value.type for value in self.values(names)]

    def describe(self, names: list[str]) -> list[Descriptor]:
        known = self._fetch()
        out = []
        for name in names:
            p = known.get(name)
            if p is None:
                out.append(Descriptor(name))
                continue
            out.append(
                Descriptor(
                    name=name,
                    type=_value(p).type,
                    description=p.description,
                    additional_constraints=f"set while running: applies {p.applies}" if p.settable else "",
                    read_only=not p.settable,
                )
            )
        return out

    def set_each(self, parameters: list[tuple[str, Value]]) -> list[SetOutcome]:
        known = self._fetch()
        return [self._set_one(name, value, known) for name, value in parameters]

    def set_atomically(self, parameters: list[tuple[str, Value]]) -> SetOutcome:
        if len(parameters) != 1:
            return False, "zendock sets one parameter at a time: use set_parameters"
        name, value = parameters[0]
        return self._set_one(name, value, self._fetch())

    def _set_one(self, name: str, value: Value, known: dict[str, ZendockDescriptor]) -> SetOutcome:
        current = known.get(name)
        if current is None:
            return False, f"{name}: no such parameter"
        try:
            wanted = parameter_values.from_ros(value.type, value.field_value, json.loads(current.value_json))
        except ValueError as exc:
            return False, f"{name}: {exc}"
        return self._store(name, json.dumps(wanted))


def _value(descriptor: ZendockDescriptor) -> Value:
    type_code, field_value = parameter_values.to_ros(json.loads(descriptor.value_json))
    return Value(type_code, field_value)


def answers_from_bus(
    session: zenoh.Session, namespace: str, owner: str, wait_s: float = PARAMETER_WAIT_S
) -> ParameterAnswers:
    """Answers for zendock's node ``owner`` in ``namespace``, asking its ``_param/list`` and ``_param/set``
    (blocking: call from a thread that may wait, never a Zenoh callback)."""

    def key(verb: str) -> str:
        return topic_key(namespace, parameter_service(owner, verb))

    def fetch() -> dict[str, ZendockDescriptor]:
        try:
            reply = call_service(session, key("list"), LIST_PARAMETERS, ListParametersRequest(), wait_s)
        except ServiceError:
            return {}  # the node does not answer: ROS 2 sees no parameters
        return {p.name: p for p in reply.parameters}

    def store(name: str, value_json: str) -> SetOutcome:
        request = SetParameterRequest(name=name, value_json=value_json)
        try:
            reply = call_service(session, key("set"), SET_PARAMETER, request, wait_s)
        except ServiceError as exc:
            return False, f"{name}: {exc}"
        return reply.successful, reply.reason

    return ParameterAnswers(fetch, store)
