"""``zendock keys list [-t] [-v] [-a]``: the keys in use, as ``ros2 topic list`` shows topics.

Keys come from the nodes' liveliness tokens (and the router's admin space when enabled). Service and
action keys are listed too, marked ``(service)`` and ``(action)``; a key seen only in the admin space is
marked ``(no token)`` and has no known type. ``--namespace`` limits the list to keys under it.

Hidden keys are left out unless ``-a``/``--include-hidden`` is given: as ROS 2 hides a name with a part
that starts with ``_``, the parts of an action (``dock_robot/_action/send_goal``, ``.../feedback``, ...)
and a node's parameter services (``battery/_param/get``) are hidden; the action itself is listed.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TextIO

from deploy.keys.connection import BusOptions, open_bus
from deploy.keys.graph import KIND_LABELS, Endpoint, KeyEntry, query_graph

GRAPH_TIMEOUT_S = 2.0
UNKNOWN_TYPE = "?"


@dataclass(frozen=True)
class ListFormat:
    show_types: bool = False
    verbose: bool = False  # implies show_types
    include_hidden: bool = False


def is_hidden(key: str) -> bool:
    """A key with a part starting with ``_`` (``dock_robot/_action/status``), as ROS 2 hides such names."""
    return any(part.startswith("_") for part in key.split("/"))


def markers(entry: KeyEntry) -> list[str]:
    found = []
    if entry.is_service:
        found.append("(service)")
    if entry.is_action:
        found.append("(action)")
    if not entry.has_token:
        found.append("(no token)")
    return found


def key_line(entry: KeyEntry, show_types: bool) -> str:
    parts = [entry.key]
    if show_types:
        parts.append(f"[{', '.join(entry.types) or UNKNOWN_TYPE}]")
    parts += markers(entry)
    return " ".join(parts)


def _nodes(endpoints: Iterable[Endpoint]) -> str:
    return ", ".join(sorted({e.node for e in endpoints}))


def endpoint_lines(entry: KeyEntry, indent: str = "  ") -> list[str]:
    """Who is on the key: publishers and subscribers of a topic, servers of a service or action."""
    lines = []
    kinds = [k for k in ("srv", "act") if entry.of_kind(k)]
    if not kinds or entry.of_kind("pub") or entry.of_kind("sub"):
        kinds = ["pub", "sub", *kinds]
    for kind in kinds:
        endpoints = entry.of_kind(kind)
        label = f"{KIND_LABELS[kind]}s ({len(endpoints)})"
        lines.append(f"{indent}{label}: {_nodes(endpoints)}".rstrip())
    if entry.anonymous:
        seen = ", ".join(KIND_LABELS[k] for k in sorted(entry.anonymous))
        lines.append(f"{indent}without a zendock token (router admin space): {seen}")
    return lines


def list_lines(entries: Iterable[KeyEntry], fmt: ListFormat) -> list[str]:
    lines = []
    for entry in entries:
        lines.append(key_line(entry, fmt.show_types or fmt.verbose))
        if fmt.verbose:
            lines += endpoint_lines(entry)
    return lines


def run_list(options: BusOptions, fmt: ListFormat, out: TextIO, err: TextIO | None = None) -> int:
    err = err or sys.stderr
    with open_bus(options) as session:
        graph = query_graph(session, GRAPH_TIMEOUT_S)
    entries = [e for e in graph.in_namespace(options.namespace) if fmt.include_hidden or not is_hidden(e.key)]
    if not entries:
        where = f" in namespace {options.namespace!r}" if options.namespace else ""
        err.write(
            f"zendock keys list: no keys announced{where} (the router answered; are services running?)\n"
        )
        return 0
    out.write("\n".join(list_lines(entries, fmt)) + "\n")
    out.flush()
    return 0
