"""Recordings as ROS 2 bags: a rosbag2 directory (``metadata.yaml`` and an MCAP file, ``cdr`` messages with
``ros2msg`` schemas), what ``ros2 bag record -s mcap`` writes, so ``ros2 bag info/play``, Foxglove and
rosbags read it.

Writing (:class:`Ros2BagLog`, what the recorder feeds with ``--format ros2``): each sample's msgpack is
decoded into its zendock message and written as the ROS 2 message of the same type in CDR
(:mod:`shared.ros2.types`), on the topic the ROS 2 bridge gives it (the key without the namespace:
``robot/scan`` -> ``/scan``). zendock's own types (contacts, collisions, detections, ...) have no ROS 2
definition and are left out, counted by type. Reading (:class:`Ros2BagRecording`) turns the CDR back into
zendock's msgpack, so ``zendock replay`` plays a ROS 2 bag onto the bus.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import yaml
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.rosbag2.errors import ReaderError, WriterError

import shared.interfaces.docking
import shared.interfaces.navigation  # noqa: F401
from deploy.recording.mcap_log import RecordedSample, split_encoding
from deploy.recording.reading import RawMessage
from shared.config_errors import ConfigError
from shared.foxglove_view import ViewMessage
from shared.names import normalise_namespace, topic_key
from shared.node import encoding_for
from shared.ros2 import types as ros_types
from shared.schema import MessageError, message_type

#: rosbag2 custom data (metadata.yaml) naming the zendock namespace the bag was recorded in.
NAMESPACE_DATA = "zendock.namespace"


def is_ros2_bag(path: str | Path) -> bool:
    """A rosbag2 directory (or its ``metadata.yaml``)."""
    p = Path(path)
    return (p.is_dir() and (p / "metadata.yaml").is_file()) or p.name == "metadata.yaml"


def ros_topic(key: str, namespace: str) -> str:
    """``robot/camera/image_raw`` in namespace ``robot`` -> ``/camera/image_raw``."""
    prefix = normalise_namespace(namespace)
    relative = key[len(prefix) + 1 :] if prefix and key.startswith(prefix + "/") else key
    return "/" + relative.strip("/")


class Ros2BagLog:
    """A ROS 2 bag being written; the recorder's sink for ``--format ros2`` (same calls as the MCAP log)."""

    def __init__(self, output: str | Path, namespace: str) -> None:
        self.path = Path(output)
        self._namespace = namespace
        try:
            self._writer = Writer(self.path, version=Writer.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP)
            self._writer.open()
        except (WriterError, OSError) as exc:
            raise OSError(f"{self.path}: cannot write a ROS 2 bag here ({exc})") from None
        self._writer.set_custom_data(NAMESPACE_DATA, namespace)
        self._connections: dict[tuple[str, str], Any] = {}
        self.skipped: Counter[str] = Counter()
        self.raw_messages = 0
        self.view_messages = 0
        self._finished = False

    def write_sample(self, sample: RecordedSample) -> None:
        _, type_name = split_encoding(sample.encoding)
        ros_type = ros_types.jazzy_name(type_name)
        if not type_name or not ros_types.knows(ros_type):
            self.skipped[type_name or "untyped"] += 1
            return
        try:
            payload = ros_types.to_cdr(message_type(type_name).decode(sample.payload), ros_type)
        except (KeyError, MessageError, ros_types.Ros2TypeError):
            self.skipped[f"{type_name} (undecodable)"] += 1
            return
        topic = ros_topic(sample.key, self._namespace)
        connection = self._connections.get((topic, ros_type))
        if connection is None:
            connection = self._writer.add_connection(topic, ros_type, typestore=ros_types.typestore())
            self._connections[(topic, ros_type)] = connection
        self._writer.write(connection, sample.log_time_ns, payload)
        self.raw_messages += 1

    def write_view(self, message: ViewMessage, log_time_ns: int) -> None:
        """Foxglove views are for zendock's own format; a ROS 2 bag carries the ROS 2 messages only."""

    def add_metadata(self, name: str, values: dict[str, Any]) -> None:
        for key, value in values.items():
            self._writer.set_custom_data(f"{name}.{key}", str(value))

    def add_attachment(self, name: str, media_type: str, data: bytes, log_time_ns: int) -> None:
        """rosbag2 has no attachments: the world file stays with zendock's format."""

    def finish(self) -> None:
        if not self._finished:
            self._finished = True
            self._writer.close()


class Ros2BagRecording:
    """A ROS 2 bag read as a zendock recording (the calls ``zendock replay`` makes), messages in msgpack."""

    def __init__(self, path: str | Path) -> None:
        p = Path(path)
        self.path = p.parent if p.name == "metadata.yaml" else p
        try:
            self._reader = Reader(self.path)
            self._reader.open()
        except (ReaderError, OSError) as exc:
            raise ConfigError(f"{self.path}: not a readable ROS 2 bag ({exc})") from None
        custom = _custom_data(self.path)
        self._namespace = normalise_namespace(custom.get(NAMESPACE_DATA, ""))
        store = ros_types.typestore()
        self._connections = [
            c
            for c in self._reader.connections
            if c.msgtype in store.types and _zendock_type(c.msgtype) is not None
        ]
        self.unknown_types = sorted(
            {c.msgtype for c in self._reader.connections} - {c.msgtype for c in self._connections}
        )

    def __enter__(self) -> Ros2BagRecording:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._reader.close()

    def _key(self, topic: str) -> str:
        return topic_key(self._namespace, topic.strip("/"))

    def recording_info(self) -> dict[str, str]:
        return {"namespace": self._namespace}

    def raw_keys(self) -> dict[str, int]:
        counts: dict[str, int] = {}
        for c in self._connections:
            counts[self._key(c.topic)] = counts.get(self._key(c.topic), 0) + c.msgcount
        return counts

    def raw_messages(self, keys: Sequence[str] | None = None) -> Iterator[RawMessage]:
        wanted = set(keys) if keys else None
        connections = [c for c in self._connections if wanted is None or self._key(c.topic) in wanted]
        if not connections:
            return
        for connection, timestamp, data in self._reader.messages(connections=connections):
            zendock_type = _zendock_type(connection.msgtype)
            assert zendock_type is not None
            try:
                msg = ros_types.from_ros(ros_types.from_cdr(data, connection.msgtype), zendock_type)
            except (ros_types.Ros2TypeError, MessageError) as exc:
                raise ConfigError(
                    f"{self.path}: a {connection.msgtype} on {connection.topic} does not read: {exc}"
                ) from None
            type_name = msg.TYPE_NAME
            yield RawMessage(
                self._key(connection.topic),
                str(encoding_for(type_name)),
                type_name,
                msg.encode(),
                timestamp,
                0,
            )


def _custom_data(bag: Path) -> dict[str, str]:
    """``custom_data`` of the bag's metadata.yaml (rosbag2's place for a recorder's own notes)."""
    try:
        info = yaml.safe_load((bag / "metadata.yaml").read_text(encoding="utf-8"))[
            "rosbag2_bagfile_information"
        ]
    except (OSError, yaml.YAMLError, KeyError, TypeError):
        return {}
    custom = info.get("custom_data") if isinstance(info, dict) else None
    return {str(k): str(v) for k, v in custom.items()} if isinstance(custom, dict) else {}


def _zendock_type(ros_type: str) -> Any:
    try:
        return message_type(ros_types.zendock_name(ros_type))
    except KeyError:
        return None
