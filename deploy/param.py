"""``zendock param list|get|set NODE ...``: a running node's parameters, like ``ros2 param``.

Each node answers ``<ns>/<node>/_param/{list,get,set}`` (:mod:`shared.parameter_server`). ``set`` parses
VALUE as YAML, as ``-p NAME=VALUE`` does at start-up, and the node validates it with the same model. Only
the parameters a service marks runtime-settable change; ``list`` says which, and when a change applies.
Exit codes: 0 done, 1 the node did not answer, 2 refused (unknown name, not settable, bad value).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any, TextIO

from deploy.keys.connection import BusOptions, open_bus
from deploy.keys.errors import EXIT_NOT_FOUND, EXIT_USAGE, KeysError
from deploy.nodes import resolve_node
from shared.interfaces.parameters import (
    GET_PARAMETER,
    LIST_PARAMETERS,
    SET_PARAMETER,
    GetParameterRequest,
    ListParametersRequest,
    ParameterDescriptor,
    SetParameterRequest,
)
from shared.names import parameter_service, topic_key
from shared.node import ServiceError, ServiceType, ServiceUnavailable, call_service
from shared.runtime import parse_parameter_value

REQUEST_TIMEOUT_S = 3.0


#: VALUE read as ``-p`` reads it.
parse_value = parse_parameter_value


def service_key(node_display: str, verb: str) -> str:
    """``/robot1/battery`` + ``set`` -> ``robot1/battery/_param/set``."""
    namespace, _, node = node_display.strip("/").rpartition("/")
    return topic_key(namespace, parameter_service(node, verb))


def settable_text(p: ParameterDescriptor) -> str:
    return f"yes, {p.applies}" if p.settable else "no"


def table_lines(parameters: Sequence[ParameterDescriptor]) -> list[str]:
    """NAME, VALUE, SETTABLE columns, as ``param list`` prints them."""
    rows = [("NAME", "VALUE", "SETTABLE")] + [(p.name, p.value_json, settable_text(p)) for p in parameters]
    widths = [max(len(row[i]) for row in rows) for i in range(2)]
    return [f"{n:<{widths[0]}}  {v:<{widths[1]}}  {s}".rstrip() for n, v, s in rows]


def descriptor_json(p: ParameterDescriptor) -> dict[str, Any]:
    return {
        "name": p.name,
        "value": json.loads(p.value_json),
        "settable": p.settable,
        "applies": p.applies,
        "description": p.description,
    }


def _call(options: BusOptions, node: str, verb: str, srv: ServiceType[Any, Any], request: Any) -> Any:
    key = service_key(node, verb)
    with open_bus(options) as session:
        try:
            return call_service(session, key, srv, request, REQUEST_TIMEOUT_S)
        except ServiceUnavailable:
            raise KeysError(
                f"node {node} did not answer on {key} (is it running? zendock nodes list)", EXIT_NOT_FOUND
            ) from None
        except ServiceError as exc:
            reason = str(exc).removeprefix(f"{key}: ")
            raise KeysError(f"{node}: {reason}", EXIT_USAGE) from None


def run_param_list(options: BusOptions, node_name: str, as_json: bool, out: TextIO) -> int:
    node = resolve_node(node_name, options.namespace)
    response = _call(options, node, "list", LIST_PARAMETERS, ListParametersRequest())
    if as_json:
        out.write(json.dumps([descriptor_json(p) for p in response.parameters], indent=2) + "\n")
    else:
        out.write("\n".join(table_lines(response.parameters)) + "\n")
    return 0


def run_param_get(options: BusOptions, node_name: str, name: str, as_json: bool, out: TextIO) -> int:
    node = resolve_node(node_name, options.namespace)
    p = _call(options, node, "get", GET_PARAMETER, GetParameterRequest(name=name)).parameter
    out.write(json.dumps(descriptor_json(p)) + "\n" if as_json else f"{p.name}: {p.value_json}\n")
    return 0


def run_param_set(options: BusOptions, node_name: str, name: str, value_text: str, out: TextIO) -> int:
    node = resolve_node(node_name, options.namespace)
    value = parse_value(value_text)
    request = SetParameterRequest(name=name, value_json=json.dumps(value, default=str))
    response = _call(options, node, "set", SET_PARAMETER, request)
    if not response.successful:
        raise KeysError(f"{node}: {response.reason}", EXIT_USAGE)
    p = response.parameter
    out.write(f"Set parameter successful: {p.name} = {p.value_json} (applies {p.applies})\n")
    return 0
