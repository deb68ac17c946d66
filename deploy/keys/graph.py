"""The bus as a graph of keys: who publishes, subscribes, serves each key, and with which type.

The source of truth is the liveliness tokens every zendock node declares (``@zendock/<kind>/<ns>/<node>/
<type>/<key>``, see :mod:`shared.names`). Where the router's admin space is enabled
(``adminspace/enabled: true``), its publisher, subscriber and queryable lists add the keys of Zenoh
applications that declare no token; they carry no type and no node name.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import zenoh

from shared.names import GRAPH_PREFIX, GraphEntry, parse_token_key

#: Endpoint kinds as they read in output.
KIND_LABELS = {"pub": "publisher", "sub": "subscriber", "srv": "service server", "act": "action server"}
#: Admin-space lists of a Zenoh router and the endpoint kind each one holds.
ADMIN_LISTS = (("publisher", "pub"), ("subscriber", "sub"), ("queryable", "srv"))


def node_display_name(namespace: str, node: str) -> str:
    """``/robot1/simulator``, or ``/simulator`` with no namespace (the ROS spelling of a node)."""
    return f"/{namespace}/{node}" if namespace else f"/{node}"


@dataclass(frozen=True, order=True)
class Endpoint:
    """One declared endpoint on a key: a node's publisher, subscription, service or action server."""

    kind: str
    node: str  # display name, e.g. /robot1/simulator
    type_name: str


@dataclass
class KeyEntry:
    """Everything known about one key."""

    key: str
    endpoints: list[Endpoint] = field(default_factory=list)
    #: Endpoint kinds seen only in the router's admin space, with no zendock token for that kind.
    anonymous: set[str] = field(default_factory=set)

    def of_kind(self, kind: str) -> list[Endpoint]:
        return sorted(e for e in self.endpoints if e.kind == kind)

    @property
    def types(self) -> list[str]:
        return sorted({e.type_name for e in self.endpoints if e.type_name})

    @property
    def topic_types(self) -> list[str]:
        """Types announced by publishers and subscribers (what ``pub`` may send on the key)."""
        return sorted({e.type_name for e in self.endpoints if e.kind in ("pub", "sub") and e.type_name})

    @property
    def is_service(self) -> bool:
        return any(e.kind == "srv" for e in self.endpoints)

    @property
    def is_action(self) -> bool:
        return any(e.kind == "act" for e in self.endpoints)

    @property
    def has_token(self) -> bool:
        return bool(self.endpoints)


@dataclass
class Graph:
    """Keys in use and nodes that are up."""

    keys: dict[str, KeyEntry] = field(default_factory=dict)
    nodes: list[str] = field(default_factory=list)

    def entry(self, key: str) -> KeyEntry | None:
        return self.keys.get(key)

    def matching(self, key_expr: str) -> list[KeyEntry]:
        """Entries whose key intersects ``key_expr`` (wildcards allowed), sorted by key."""
        expr = zenoh.KeyExpr(key_expr)
        return [self.keys[k] for k in sorted(self.keys) if expr.intersects(zenoh.KeyExpr(k))]

    def in_namespace(self, namespace: str) -> list[KeyEntry]:
        """Entries under ``namespace`` (all of them for the root namespace), sorted by key."""
        if not namespace:
            return [self.keys[k] for k in sorted(self.keys)]
        return [self.keys[k] for k in sorted(self.keys) if k == namespace or k.startswith(namespace + "/")]


def build_graph(token_keys: Iterable[str], admin_endpoints: Iterable[tuple[str, str]] = ()) -> Graph:
    """Assemble the graph from liveliness token keys and ``(kind, key)`` pairs from the admin space."""
    graph = Graph()
    nodes: set[str] = set()
    for token_key in token_keys:
        parsed: GraphEntry | None = parse_token_key(token_key)
        if parsed is None:
            continue
        name = node_display_name(parsed.namespace, parsed.node)
        if parsed.kind == "node":
            nodes.add(name)
            continue
        entry = graph.keys.setdefault(parsed.key, KeyEntry(parsed.key))
        endpoint = Endpoint(parsed.kind, name, parsed.type_name)
        if endpoint not in entry.endpoints:
            entry.endpoints.append(endpoint)
    for kind, key in admin_endpoints:
        if key.startswith("@"):
            continue  # the admin space's own queryables and liveliness machinery
        entry = graph.keys.setdefault(key, KeyEntry(key))
        if not any(e.kind == kind for e in entry.endpoints):
            entry.anonymous.add(kind)
    graph.nodes = sorted(nodes)
    return graph


def admin_key(admin_sample_key: str, list_name: str) -> str | None:
    """``@/<zid>/router/publisher/robot1/odom`` -> ``robot1/odom`` (``None`` for other admin keys)."""
    parts = admin_sample_key.split("/", 4)
    if len(parts) < 5 or parts[0] != "@" or parts[2] != "router" or parts[3] != list_name:
        return None
    return parts[4]


def query_graph(session: zenoh.Session, timeout_s: float = 2.0) -> Graph:
    """Ask the bus: every ``@zendock`` liveliness token, plus the routers' admin space when it answers."""
    tokens = [
        str(reply.ok.key_expr)
        for reply in session.liveliness().get(f"{GRAPH_PREFIX}/**", timeout=timeout_s)
        if reply.ok is not None
    ]
    admin: set[tuple[str, str]] = set()
    for list_name, kind in ADMIN_LISTS:
        replies = session.get(
            f"@/*/router/{list_name}/**",
            timeout=timeout_s,
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
        )
        for reply in replies:
            if reply.ok is None:
                continue
            key = admin_key(str(reply.ok.key_expr), list_name)
            if key is not None:
                admin.add((kind, key))
    return build_graph(tokens, sorted(admin))
