"""``zendock keys info KEY``: a key's type and who is on it, as ``ros2 topic info`` shows a topic.

A wildcard key shows every matching key. A key nothing announces is an error (exit 1).
"""

from __future__ import annotations

from typing import TextIO

from deploy.keys.connection import BusOptions, open_bus, resolve_key
from deploy.keys.errors import KeysError
from deploy.keys.graph import KIND_LABELS, KeyEntry, query_graph

GRAPH_TIMEOUT_S = 2.0
_COUNT_LABELS = (
    ("pub", "Publisher count"),
    ("sub", "Subscription count"),
    ("srv", "Service server count"),
    ("act", "Action server count"),
)


def info_lines(entry: KeyEntry) -> list[str]:
    types = entry.types
    if not types:
        type_line = "Type: unknown (no zendock token)"
    elif len(types) == 1:
        type_line = f"Type: {types[0]}"
    else:
        type_line = f"Types: {', '.join(types)}"
    lines = [f"Key: {entry.key}", type_line]
    for kind, label in _COUNT_LABELS:
        endpoints = entry.of_kind(kind)
        if kind in ("srv", "act") and not endpoints:
            continue
        lines.append(f"{label}: {len(endpoints)}")
        for endpoint in endpoints:
            suffix = f" [{endpoint.type_name}]" if len(types) > 1 else ""
            lines.append(f"    {endpoint.node}{suffix}")
    if entry.anonymous:
        seen = ", ".join(KIND_LABELS[kind] for kind in sorted(entry.anonymous))
        lines.append(f"Also in the router's admin space without a zendock token: {seen}")
    return lines


def run_info(options: BusOptions, key_text: str, out: TextIO) -> int:
    key = resolve_key(options.namespace, key_text)
    with open_bus(options) as session:
        graph = query_graph(session, GRAPH_TIMEOUT_S)
    entries = graph.matching(key)
    if not entries:
        raise KeysError(
            f"unknown key {key!r}: nothing announces it ('zendock keys list' shows the keys in use)"
        )
    blocks = ["\n".join(info_lines(entry)) for entry in entries]
    out.write("\n\n".join(blocks) + "\n")
    out.flush()
    return 0
