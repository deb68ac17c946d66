"""rmw_zenoh's wire conventions (ROS 2 Jazzy): data keys, graph tokens, QoS strings and attachments.

A ROS 2 node on rmw_zenoh publishes a topic on the key ``<domain>/<topic>/<dds type>/<type hash>``
and announces every node, publisher, subscription, service and client with a liveliness token::

    @ros2_lv/<domain>/<session id>/<node id>/<entity id>/<kind>/<enclave>/<namespace>/<node>
        [/<topic or service>/<dds type>/<type hash>/<qos>]        (endpoints only)

where names have their slashes turned into ``%`` (the empty namespace and enclave are a lone ``%``).
Each sample carries an attachment: the publisher's sequence number (the first is 1) and source timestamp
(int64, little endian) and its 16-byte gid after a one-byte length; the gid is the XXH3-128 hash of the
entity's liveliness token key (:func:`entity_gid`). Namespaces are rcl's canonical form only
(:func:`namespace_error`). This module writes and reads those forms and nothing else: no Zenoh, no
message types.
"""

from __future__ import annotations

import enum
import re
import struct
from dataclasses import dataclass

import xxhash

ADMIN_SPACE = "@ros2_lv"
GID_SIZE = 16


class EntityKind(enum.StrEnum):
    NODE = "NN"
    PUBLISHER = "MP"
    SUBSCRIPTION = "MS"
    SERVICE = "SS"
    CLIENT = "SC"


def mangle(name: str) -> str:
    """A ROS name as one key chunk: ``/a/b`` -> ``%a%b``; the root or empty name is ``%``."""
    if not name or name == "/":
        return "%"
    return name.replace("/", "%")


def demangle(chunk: str) -> str:
    """The inverse of :func:`mangle` for topic names (always absolute)."""
    if not chunk or chunk == "%":
        return "/"
    name = chunk.replace("%", "/")
    return name if name.startswith("/") else "/" + name


def dds_type_name(ros_type: str) -> str:
    """``sensor_msgs/msg/BatteryState`` -> ``sensor_msgs::msg::dds_::BatteryState_`` (as rosidl names it)."""
    package, kind, name = _split_type(ros_type)
    return f"{package}::{kind}::dds_::{name}_"


def ros_type_name(dds_type: str) -> str:
    """The inverse of :func:`dds_type_name`; ValueError for anything else."""
    parts = dds_type.split("::")
    if len(parts) != 4 or parts[2] != "dds_" or not parts[3].endswith("_") or len(parts[3]) < 2:
        raise ValueError(f"not a DDS type name: {dds_type!r}")
    return f"{parts[0]}/{parts[1]}/{parts[3][:-1]}"


def _split_type(ros_type: str) -> tuple[str, str, str]:
    parts = ros_type.split("/")
    if len(parts) != 3 or not all(parts) or parts[1] not in ("msg", "srv", "action"):
        raise ValueError(f"not a ROS 2 type name (package/msg/Name): {ros_type!r}")
    return parts[0], parts[1], parts[2]


#: One token of a ROS name (rmw's validation rules): a letter or underscore, then letters, digits, underscores.
_TOKEN = r"[A-Za-z_][A-Za-z0-9_]*"
_CANONICAL_NAMESPACE = re.compile(rf"/|(/{_TOKEN})+")


def namespace_error(namespace: str) -> str | None:
    """Why ``namespace`` is not in rcl's canonical form (``/`` or ``/a/b``: a leading slash, no trailing or
    doubled slash, tokens of letters, digits and underscores not starting with a digit); ``None`` if it is.

    rmw_zenoh receives namespaces from rcl, which has already validated and expanded them, and mangles them
    as they are; a name in any other form would give keys no ROS 2 node makes."""
    if _CANONICAL_NAMESPACE.fullmatch(namespace):
        return None
    if not namespace.startswith("/"):
        return f"{namespace!r} must start with '/' (e.g. '/{namespace.strip('/')}')"
    if namespace.endswith("/"):
        return f"{namespace!r} must not end with '/' (e.g. '/{namespace.strip('/')}')"
    if "//" in namespace:
        return f"{namespace!r} must not contain '//'"
    bad = next(t for t in namespace[1:].split("/") if not re.fullmatch(_TOKEN, t))
    return (
        f"{namespace!r}: {bad!r} is not a ROS name token (letters, digits and '_', not starting with a digit)"
    )


def qualified_name(namespace: str, name: str) -> str:
    """A relative topic name resolved in a canonical ROS namespace: (``/robot``, ``scan``) -> ``/robot/scan``."""
    if name.startswith("/"):
        return name
    return f"{'' if namespace == '/' else namespace}/{name}"


def data_key(domain_id: int, topic: str, ros_type: str, type_hash: str) -> str:
    """The key a topic's samples travel on (``topic`` is absolute, e.g. ``/battery_status``)."""
    return f"{domain_id}/{topic.strip('/')}/{dds_type_name(ros_type)}/{type_hash}"


# --- QoS ------------------------------------------------------------------------------------------


class Reliability(enum.IntEnum):
    RELIABLE = 1
    BEST_EFFORT = 2


class Durability(enum.IntEnum):
    TRANSIENT_LOCAL = 1
    VOLATILE = 2


@dataclass(frozen=True)
class QosProfile:
    """The QoS an endpoint announces in its token: ``<rel>:<dur>:<hist>,<depth>:<deadline>:<lifespan>:<liveliness>``.

    Defaults (reliable, volatile, keep last) are written as empty fields, as rmw_zenoh does; deadline,
    lifespan and liveliness are always the defaults here.
    """

    reliability: Reliability = Reliability.RELIABLE
    durability: Durability = Durability.VOLATILE
    depth: int = 10

    def encode(self) -> str:
        reliability = "" if self.reliability is Reliability.RELIABLE else str(int(self.reliability))
        durability = "" if self.durability is Durability.VOLATILE else str(int(self.durability))
        return f"{reliability}:{durability}:,{self.depth}:,:,:,,"

    @classmethod
    def decode(cls, text: str) -> QosProfile:
        parts = text.split(":")
        if len(parts) != 6:
            raise ValueError(f"QoS {text!r}: expected 6 ':'-separated fields")
        try:
            reliability = Reliability(int(parts[0])) if parts[0] not in ("", "0") else Reliability.RELIABLE
            durability = Durability(int(parts[1])) if parts[1] not in ("", "0") else Durability.VOLATILE
            _kind, _, depth = parts[2].partition(",")
            return cls(reliability, durability, int(depth) if depth else 10)
        except ValueError as exc:
            raise ValueError(f"QoS {text!r}: {exc}") from None


RELIABLE = QosProfile()
SENSOR_DATA = QosProfile(Reliability.BEST_EFFORT, Durability.VOLATILE, 5)
LATCHED = QosProfile(Reliability.RELIABLE, Durability.TRANSIENT_LOCAL, 1)


# --- graph tokens --------------------------------------------------------------------------------


@dataclass(frozen=True)
class GraphNode:
    domain_id: int
    session_id: str
    node_id: int
    name: str
    namespace: str = "/"
    enclave: str = "/"

    def token_key(self) -> str:
        return (
            f"{ADMIN_SPACE}/{self.domain_id}/{self.session_id}/{self.node_id}/{self.node_id}/"
            f"{EntityKind.NODE}/{mangle(self.enclave)}/{mangle(self.namespace)}/{mangle(self.name)}"
        )


@dataclass(frozen=True)
class Endpoint:
    """A publisher, subscription, service or client of a node, as its liveliness token says."""

    node: GraphNode
    entity_id: int
    kind: EntityKind
    topic: str
    ros_type: str
    type_hash: str
    qos: QosProfile = RELIABLE

    def token_key(self) -> str:
        n = self.node
        return (
            f"{ADMIN_SPACE}/{n.domain_id}/{n.session_id}/{n.node_id}/{self.entity_id}/{self.kind}/"
            f"{mangle(n.enclave)}/{mangle(n.namespace)}/{mangle(n.name)}/{mangle(self.topic)}/"
            f"{dds_type_name(self.ros_type)}/{self.type_hash}/{self.qos.encode()}"
        )


def parse_endpoint_token(key: str) -> Endpoint:
    """An endpoint token's fields; ValueError naming what is wrong for anything else (nodes included)."""
    parts = key.split("/")
    if len(parts) != 13 or parts[0] != ADMIN_SPACE:
        raise ValueError(f"not an rmw_zenoh endpoint token: {key!r}")
    try:
        kind = EntityKind(parts[5])
        if kind is EntityKind.NODE:
            raise ValueError("a node token has no endpoint")
        node = GraphNode(
            int(parts[1]),
            parts[2],
            int(parts[3]),
            demangle(parts[8]).lstrip("/"),
            demangle(parts[7]),
            demangle(parts[6]),
        )
        return Endpoint(
            node,
            int(parts[4]),
            kind,
            demangle(parts[9]),
            ros_type_name(parts[10]),
            parts[11],
            QosProfile.decode(parts[12]),
        )
    except ValueError as exc:
        raise ValueError(f"endpoint token {key!r}: {exc}") from None


# --- attachments ---------------------------------------------------------------------------------


def entity_gid(token_key: str) -> bytes:
    """An entity's 16-byte gid, as rmw_zenoh makes it (``liveliness_utils.cpp``, ``Entity::Entity``): the
    XXH3-128 hash (seed 0) of its liveliness token key, the low 64 bits then the high 64 bits, each in the
    host's byte order (little endian on every platform ROS 2 Jazzy ships for)."""
    digest = xxhash.xxh3_128_intdigest(token_key.encode())
    return digest.to_bytes(GID_SIZE, "little")


_HEAD = struct.Struct("<qqB")


@dataclass(frozen=True)
class Attachment:
    """What rides with each sample (``attachment_helpers.cpp``): sequence number, source time, publisher gid."""

    sequence_number: int
    source_timestamp_ns: int
    gid: bytes

    def encode(self) -> bytes:
        if len(self.gid) != GID_SIZE:
            raise ValueError(f"a gid is {GID_SIZE} bytes, not {len(self.gid)}")
        return _HEAD.pack(self.sequence_number, self.source_timestamp_ns, GID_SIZE) + self.gid

    @classmethod
    def decode(cls, data: bytes) -> Attachment:
        if len(data) != _HEAD.size + GID_SIZE:
            raise ValueError(f"an attachment is {_HEAD.size + GID_SIZE} bytes, not {len(data)}")
        sequence, stamp, size = _HEAD.unpack_from(data)
        if size != GID_SIZE:
            raise ValueError(f"attachment gid length {size}, expected {GID_SIZE}")
        return cls(sequence, stamp, bytes(data[_HEAD.size :]))
