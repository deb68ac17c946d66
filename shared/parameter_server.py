"""A node's parameters on the bus: ``<ns>/<node>/_param/{list,get,set}`` answered from a :class:`ParameterTable`.

:mod:`shared.runtime` (and :mod:`shared.composition`) attach one to every service's node after building
the service, so every service answers ``zendock param``. A service that applies a change at once
registers a listener when it is built, by defining ``on_parameter_set(name, value)``
(:class:`ParameterListener`); the server registers it for the service's runtime-settable parameters.
The requests run on the node's executor, so a change never races the service's callbacks.
"""

from __future__ import annotations

import json
from typing import Any, Protocol, runtime_checkable

import msgspec

from shared.interfaces.parameters import (
    GET_PARAMETER,
    LIST_PARAMETERS,
    SET_PARAMETER,
    GetParameterRequest,
    GetParameterResponse,
    ListParametersRequest,
    ListParametersResponse,
    ParameterDescriptor,
    SetParameterRequest,
    SetParameterResponse,
)
from shared.names import parameter_service
from shared.node import Node, ServiceServer
from shared.parameters import ParameterInfo, ParameterRefused, ParameterTable


@runtime_checkable
class ParameterListener(Protocol):
    """A service that applies runtime parameter changes itself (``ValueError``: refuse the change)."""

    def on_parameter_set(self, name: str, value: Any) -> None: ...


def descriptor(info: ParameterInfo) -> ParameterDescriptor:
    return ParameterDescriptor(
        name=info.name,
        value_json=info.value_json,
        settable=info.settable,
        applies=info.applies,
        description=info.description,
    )


class ParameterServer:
    """The three parameter services of one node over one :class:`ParameterTable`."""

    def __init__(self, node: Node, table: ParameterTable) -> None:
        self.table = table
        self._log = node.log
        self._servers: list[ServiceServer[Any, Any]] = [
            node.create_service(LIST_PARAMETERS, parameter_service(node.name, "list"), self._on_list),
            node.create_service(GET_PARAMETER, parameter_service(node.name, "get"), self._on_get),
            node.create_service(SET_PARAMETER, parameter_service(node.name, "set"), self._on_set),
        ]

    def _on_list(self, _request: ListParametersRequest) -> ListParametersResponse:
        return ListParametersResponse(parameters=[descriptor(info) for info in self.table.describe()])

    def _on_get(self, request: GetParameterRequest) -> GetParameterResponse:
        return GetParameterResponse(
            parameter=descriptor(self.table.get(request.name))
        )  # ParameterRefused: error reply

    def _on_set(self, request: SetParameterRequest) -> SetParameterResponse:
        try:
            value = json.loads(request.value_json)
        except (ValueError, RecursionError):
            return SetParameterResponse(
                successful=False, reason=f"{request.name}: value is not JSON: {request.value_json!r}"
            )
        try:
            info = self.table.set(request.name, value)
        except ParameterRefused as exc:
            self._log.info("parameter change refused: %s", exc)
            return SetParameterResponse(successful=False, reason=str(exc))
        self._log.info("parameter %s set to %s (applies %s)", info.name, info.value_json, info.applies)
        return SetParameterResponse(successful=True, parameter=descriptor(info))

    def close(self) -> None:
        for server in self._servers:
            server.undeclare()
        self._servers.clear()


def attach_parameters(node: Node, params: msgspec.Struct, service: object) -> ParameterServer:
    """Serve ``params`` on ``node``; a ``service`` with ``on_parameter_set`` hears every accepted change."""
    table = ParameterTable(params)
    if isinstance(service, ParameterListener) and table.settable_names():
        table.on_set(table.settable_names(), service.on_parameter_set)
    return ParameterServer(node, table)
