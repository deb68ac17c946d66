"""Key expressions: topics, services, actions and the graph's liveliness tokens.

Topic keys follow zenoh-bridge-ros2dds: ``<namespace>/<topic>`` with no leading slash, or just
``<topic>`` when the namespace is empty, so several robots share one Zenoh network by namespace.

Every service announces itself and each of its endpoints with a liveliness token under the hermetic
prefix ``@zendock``. Chunks that may be empty or hold slashes are encoded (``/`` -> ``%``, empty -> ``%``)
so each token splits back unambiguously::

    @zendock/node/<ns>/<node>                                  the service is up and ready
    @zendock/<kind>/<ns>/<node>/<type>/<key...>                kind: pub | sub | srv | act

A node's runtime parameters are three services under the node's own name, beside the ``_action`` parts of
an action (:func:`parameter_service`): ``<ns>/<node>/_param/list``, ``.../get`` and ``.../set``.
"""

from __future__ import annotations

import re

import msgspec

GRAPH_PREFIX = "@zendock"
ENDPOINT_KINDS = ("pub", "sub", "srv", "act")
_CHUNK_RE = re.compile(r"^[A-Za-z0-9_\-.~]+$")


def normalise_namespace(namespace: str) -> str:
    """Strip slashes: ``/robot1/`` -> ``robot1``; ``""`` and ``/`` -> ``""``. Rejects wildcards and empty chunks."""
    ns = namespace.strip("/")
    if ns and not all(_CHUNK_RE.match(chunk) for chunk in ns.split("/")):
        raise ValueError(f"namespace {namespace!r}: use letters, digits, '_', '-', '.' and '/' between parts")
    return ns


def topic_key(namespace: str, topic: str) -> str:
    """The Zenoh key of a topic (or service, or action) in a namespace."""
    topic = topic.strip("/")
    if not topic:
        raise ValueError("topic name is empty")
    ns = normalise_namespace(namespace)
    return f"{ns}/{topic}" if ns else topic


def encode_chunk(text: str) -> str:
    """One key chunk for a value that may be empty or contain slashes."""
    return text.replace("/", "%") if text else "%"


def decode_chunk(chunk: str) -> str:
    return "" if chunk == "%" else chunk.replace("%", "/")


def node_token_key(namespace: str, node_name: str) -> str:
    """The liveliness token a service declares once it is ready (a launcher's health check)."""
    return f"{GRAPH_PREFIX}/node/{encode_chunk(normalise_namespace(namespace))}/{encode_chunk(node_name)}"


def stats_key(namespace: str, node_name: str) -> str:
    """Where a node answers with its message counters (``@zendock/stats/<ns>/<node>``; ``zendock bench messages``)."""
    return f"{GRAPH_PREFIX}/stats/{encode_chunk(normalise_namespace(namespace))}/{encode_chunk(node_name)}"


#: The verbs of a node's parameter services (:mod:`shared.parameter_server`).
PARAMETER_VERBS = ("list", "get", "set")


def parameter_service(node_name: str, verb: str) -> str:
    """The service name (relative to the namespace) of a node's parameter ``verb``: ``battery/_param/set``."""
    if verb not in PARAMETER_VERBS:
        raise ValueError(f"parameter verb must be one of {PARAMETER_VERBS}, got {verb!r}")
    return f"{node_name.strip('/')}/_param/{verb}"


def endpoint_token_key(kind: str, namespace: str, node_name: str, type_name: str, key: str) -> str:
    if kind not in ENDPOINT_KINDS:
        raise ValueError(f"endpoint kind must be one of {ENDPOINT_KINDS}, got {kind!r}")
    return (
        f"{GRAPH_PREFIX}/{kind}/{encode_chunk(normalise_namespace(namespace))}/"
        f"{encode_chunk(node_name)}/{encode_chunk(type_name)}/{key}"
    )


class GraphEntry(msgspec.Struct, frozen=True):
    """One parsed liveliness token: a node, or one of its endpoints."""

    kind: str  # node | pub | sub | srv | act
    namespace: str
    node: str
    type_name: str = ""
    key: str = ""


def parse_token_key(token_key: str) -> GraphEntry | None:
    """Inverse of :func:`node_token_key` / :func:`endpoint_token_key`; ``None`` for foreign keys."""
    parts = token_key.split("/")
    if len(parts) < 4 or parts[0] != GRAPH_PREFIX:
        return None
    kind = parts[1]
    if kind == "node" and len(parts) == 4:
        return GraphEntry("node", decode_chunk(parts[2]), decode_chunk(parts[3]))
    if kind in ENDPOINT_KINDS and len(parts) >= 6:
        return GraphEntry(
            kind, decode_chunk(parts[2]), decode_chunk(parts[3]), decode_chunk(parts[4]), "/".join(parts[5:])
        )
    return None
