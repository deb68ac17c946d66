"""What to fuzz: every key a stack uses, with its type when the graph says it.

The graph (liveliness tokens, :mod:`shared.names`) gives keys and types: a ``sub`` token is a key someone
reads, a ``pub`` token one someone writes, an ``srv`` token a queryable with its request type, an ``act``
token an action whose send_goal, get_result and cancel_goal take requests. The names in
:mod:`shared.topics` are added in the namespace, so a key is fuzzed even when nothing announced it (its
type is then unknown and only type-agnostic payloads go there). Pure: no Zenoh here.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

from shared import topics
from shared.names import GraphEntry, topic_key

TOPIC = "topic"
REQUEST = "request"
#: A service reads a request without payload as an empty map; an action's get_result as no bytes at all.
SERVICE_EMPTY_REQUEST = b"\x80"
GET_RESULT_EMPTY_REQUEST = b""
CANCEL_GOAL_REQUEST = "action_msgs/srv/CancelGoal_Request"

KNOWN_TOPICS = (
    topics.CLOCK,
    topics.CMD_VEL,
    topics.ODOM,
    topics.TF,
    topics.TF_STATIC,
    topics.SCAN,
    topics.ULTRASONIC,
    topics.BATTERY_STATUS,
    topics.POSE2D,
    topics.DOCK_CONTACT,
    topics.COLLISIONS,
    topics.GROUND_TRUTH_POSE,
    topics.DETECTED_DOCK_POSE,
    topics.MAP,
    topics.PLAN,
)
KNOWN_SERVICES = (topics.SIM_TELEPORT, topics.SIM_STATE, topics.BATTERY_SET_STATE)
KNOWN_ACTIONS = (topics.NAVIGATE_TO_POSE, topics.DOCK_ROBOT, topics.UNDOCK_ROBOT)


@dataclass(frozen=True)
class Target:
    """One key to send malformed input to: a topic (put) or a request endpoint (get)."""

    key: str
    kind: str  # TOPIC | REQUEST
    #: The message type a subscriber expects, or the request type; None when unknown.
    type_name: str | None = None
    #: What a request without payload is read as (None for topics).
    empty_request: bytes | None = None
    #: Someone announced reading it (a sub token), or serving it (an srv or act token).
    announced: bool = False


def has_wildcards(key: str) -> bool:
    return any(chunk in ("*", "**") or "$*" in chunk for chunk in key.split("/"))


def action_targets(action_key: str, action_type: str | None, announced: bool) -> list[Target]:
    """The three request endpoints of an action (``shared.action``'s layout)."""

    def typed(suffix: str) -> str | None:
        return f"{action_type}_{suffix}" if action_type else None

    return [
        Target(
            f"{action_key}/_action/send_goal",
            REQUEST,
            typed("SendGoal_Request"),
            SERVICE_EMPTY_REQUEST,
            announced,
        ),
        Target(
            f"{action_key}/_action/get_result",
            REQUEST,
            typed("GetResult_Request"),
            GET_RESULT_EMPTY_REQUEST,
            announced,
        ),
        Target(
            f"{action_key}/_action/cancel_goal",
            REQUEST,
            CANCEL_GOAL_REQUEST,
            SERVICE_EMPTY_REQUEST,
            announced,
        ),
    ]


def graph_targets(entries: Iterable[GraphEntry], namespace: str) -> list[Target]:
    """Targets from the graph entries of ``namespace``'s nodes."""
    found: list[Target] = []
    for entry in entries:
        if entry.kind == "node" or entry.namespace != namespace:
            continue
        if entry.kind in ("sub", "pub"):
            found.append(
                Target(entry.key, TOPIC, entry.type_name or None, None, announced=entry.kind == "sub")
            )
        elif entry.kind == "srv":
            found.append(
                Target(entry.key, REQUEST, f"{entry.type_name}_Request", SERVICE_EMPTY_REQUEST, True)
            )
        elif entry.kind == "act":
            found.extend(action_targets(entry.key, entry.type_name or None, True))
    return found


def known_targets(namespace: str) -> list[Target]:
    """The names of :mod:`shared.topics` in ``namespace``, types unknown."""
    found = [Target(topic_key(namespace, name), TOPIC) for name in KNOWN_TOPICS]
    found += [
        Target(topic_key(namespace, name), REQUEST, None, SERVICE_EMPTY_REQUEST) for name in KNOWN_SERVICES
    ]
    for name in KNOWN_ACTIONS:
        found += action_targets(topic_key(namespace, name), None, False)
    return found


def merge_targets(targets: Iterable[Target], known_types: Iterable[str]) -> tuple[list[Target], list[str]]:
    """One target per (kind, key), typed when any source knows a registered type; wildcard keys set aside.

    Returns the targets sorted by key, and the keys skipped (wildcards: nothing can be put on them).
    """
    registered = set(known_types)
    merged: dict[tuple[str, str], Target] = {}
    skipped: set[str] = set()
    for target in targets:
        if has_wildcards(target.key):
            skipped.add(target.key)
            continue
        if target.type_name is not None and target.type_name not in registered:
            target = replace(target, type_name=None)
        slot = (target.kind, target.key)
        seen = merged.get(slot)
        if seen is None:
            merged[slot] = target
            continue
        announced = seen.announced or target.announced
        if seen.type_name is None or (target.announced and target.type_name is not None):
            type_name = target.type_name or seen.type_name
        else:
            type_name = seen.type_name
        merged[slot] = replace(
            seen,
            type_name=type_name,
            announced=announced,
            empty_request=seen.empty_request if seen.empty_request is not None else target.empty_request,
        )
    return sorted(merged.values(), key=lambda t: (t.key, t.kind)), sorted(skipped)
