"""``zendock nodes [list|info NODE] [--json]``: the nodes on the bus and their endpoints, like ``ros2 node``.

The graph is the one ``zendock keys list`` reads (:func:`deploy.keys.graph.query_graph`, from the
liveliness tokens every endpoint declares); here it is turned around, by node instead of by key. A node is
``/<ns>/<name>`` (``/battery`` in the root namespace). A node whose endpoints are announced but whose
ready token is not yet there is listed as ``(starting)``.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TextIO

from deploy.keys.connection import BusOptions, open_bus
from deploy.keys.errors import EXIT_NOT_FOUND, KeysError
from deploy.keys.graph import Graph, node_display_name, query_graph

GRAPH_TIMEOUT_S = 2.0
#: Sections of ``nodes info``, in ``ros2 node info``'s order, with the JSON field each one fills.
SECTIONS = (
    ("pub", "Publishers", "publishers"),
    ("sub", "Subscriptions", "subscriptions"),
    ("srv", "Services", "services"),
    ("act", "Actions", "actions"),
)


@dataclass(frozen=True, order=True)
class NodeEndpoint:
    key: str
    type_name: str


@dataclass
class NodeInfo:
    """One node: whether it said it is ready, and its endpoints by kind (``pub``/``sub``/``srv``/``act``)."""

    name: str
    ready: bool = False
    endpoints: dict[str, list[NodeEndpoint]] = field(
        default_factory=lambda: {kind: [] for kind, _l, _f in SECTIONS}
    )

    def to_json(self) -> dict[str, object]:
        body: dict[str, object] = {"name": self.name, "ready": self.ready}
        for kind, _label, json_field in SECTIONS:
            body[json_field] = [{"key": e.key, "type": e.type_name} for e in self.endpoints[kind]]
        return body


def nodes_of(graph: Graph) -> dict[str, NodeInfo]:
    """Every node in the graph by display name, each with its endpoints sorted by key."""
    nodes = {name: NodeInfo(name, ready=True) for name in graph.nodes}
    for entry in graph.keys.values():
        for endpoint in entry.endpoints:
            node = nodes.setdefault(endpoint.node, NodeInfo(endpoint.node))
            node.endpoints[endpoint.kind].append(NodeEndpoint(entry.key, endpoint.type_name))
    for node in nodes.values():
        for found in node.endpoints.values():
            found.sort()
    return dict(sorted(nodes.items()))


def resolve_node(name: str, namespace: str) -> str:
    """The display name of NODE as typed: ``/robot1/battery`` is absolute (as ``nodes list`` prints it);
    ``battery`` is in ``--namespace``."""
    if name.startswith("/"):
        return "/" + name.strip("/")
    return node_display_name(namespace, name.strip("/"))


def in_namespace(nodes: Iterable[NodeInfo], namespace: str) -> list[NodeInfo]:
    prefix = f"/{namespace}/" if namespace else "/"
    return [node for node in nodes if node.name.startswith(prefix)]


def list_lines(nodes: Iterable[NodeInfo]) -> list[str]:
    return [node.name if node.ready else f"{node.name} (starting)" for node in nodes]


def info_lines(node: NodeInfo) -> list[str]:
    """``ros2 node info``'s layout: the node, then each kind of endpoint with its keys and types."""
    lines = [node.name if node.ready else f"{node.name} (starting: no ready token yet)"]
    for kind, label, _json_field in SECTIONS:
        lines.append(f"  {label}:")
        lines += [f"    {e.key}: {e.type_name or '?'}" for e in node.endpoints[kind]]
    return lines


def run_nodes(options: BusOptions, node_name: str | None, as_json: bool, out: TextIO) -> int:
    """List the nodes (``node_name`` None) or show one; :class:`KeysError` when the node is not there."""
    with open_bus(options) as session:
        nodes = nodes_of(query_graph(session, GRAPH_TIMEOUT_S))
    if node_name is None:
        listed = in_namespace(nodes.values(), options.namespace)
        if as_json:
            out.write(json.dumps([node.to_json() for node in listed], indent=2) + "\n")
        elif listed:
            out.write("\n".join(list_lines(listed)) + "\n")
        return 0
    wanted = resolve_node(node_name, options.namespace)
    node = nodes.get(wanted)
    if node is None:
        known = ", ".join(nodes) or "none"
        raise KeysError(f"no node {wanted} on the bus (nodes: {known})", EXIT_NOT_FOUND)
    out.write(json.dumps(node.to_json(), indent=2) + "\n" if as_json else "\n".join(info_lines(node)) + "\n")
    return 0
