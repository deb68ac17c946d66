"""Writing a zendock recording as MCAP: the bus's own payloads, plus Foxglove views of them.

Layout (profile ``zendock``):

- one channel per Zenoh key (and encoding): topic = the key (``robot1/scan``), message encoding
  ``msgpack``, schema named after the ROS type (``sensor_msgs/msg/LaserScan``, schema encoding empty: msgpack
  describes itself). The payloads are the bytes that were on the bus, so a replay is exact. Channel
  metadata ``zenoh_encoding`` keeps the full Zenoh encoding; each message's MCAP ``sequence`` is the
  publisher's sequence number;
- Foxglove-schema channels (``/robot1/scan`` as ``foxglove.LaserScan``, protobuf or JSON), so the file
  opens in Foxglove or Lichtblick;
- metadata ``zendock.recording`` (what was recorded, from where), ``zendock.summary`` (counts and losses per
  key, written at the end), and the world file as attachment ``world.yaml`` when one is given.

Pure: no bus in here; the recorder feeds it samples.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from mcap.writer import CompressionType, Writer

from shared.foxglove_view import ViewMessage

PROFILE = "zendock"
LIBRARY = "zendock-record"
MSGPACK_MIME = "application/msgpack"
RAW_KEY_METADATA = "zendock_key"
ENCODING_METADATA = "zenoh_encoding"
RECORDING_METADATA = "zendock.recording"
SUMMARY_METADATA = "zendock.summary"
WORLD_ATTACHMENT = "world.yaml"
COMPRESSIONS = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}


@dataclass(frozen=True, slots=True)
class RecordedSample:
    """One sample as it came off the bus: key, Zenoh encoding text, payload, arrival time, number."""

    key: str
    encoding: str
    payload: bytes
    log_time_ns: int
    sequence: int | None = None


def split_encoding(encoding: str) -> tuple[str, str]:
    """``("application/msgpack", "sensor_msgs/msg/Range")`` from ``application/msgpack;sensor_msgs/msg/Range``."""
    mime, _, schema = encoding.partition(";")
    return mime, schema


def message_encoding_of(mime: str) -> str:
    """MCAP's name for a Zenoh mime type: ``msgpack`` for zendock's messages, else the mime itself."""
    if mime == MSGPACK_MIME:
        return "msgpack"
    return mime or "application/octet-stream"


class McapLog:
    """An MCAP file being written; channels and schemas are registered on first use."""

    def __init__(
        self, output: str | Path | IO[bytes], compression: str = "zstd", chunk_size: int = 1024 * 1024
    ) -> None:
        if compression not in COMPRESSIONS:
            raise ValueError(f"compression must be one of {sorted(COMPRESSIONS)}, got {compression!r}")
        self._file: IO[bytes] | None = None
        if isinstance(output, (str, Path)):
            self._file = open(output, "wb")  # noqa: SIM115 - closed in finish()
            stream: IO[bytes] = self._file
        else:
            stream = output
        self._writer = Writer(stream, chunk_size=chunk_size, compression=COMPRESSIONS[compression])
        self._writer.start(profile=PROFILE, library=LIBRARY)
        self._schemas: dict[tuple[str, str], int] = {}
        self._raw_channels: dict[tuple[str, str], int] = {}
        self._view_channels: dict[str, int] = {}
        self._last_log_time_ns = 0
        self.raw_messages = 0
        self.view_messages = 0
        self._finished = False

    def _schema_id(self, name: str, encoding: str, data: bytes) -> int:
        schema_id = self._schemas.get((name, encoding))
        if schema_id is None:
            schema_id = self._writer.register_schema(name=name, encoding=encoding, data=data)
            self._schemas[(name, encoding)] = schema_id
        return schema_id

    def _log_time(self, log_time_ns: int) -> int:
        """Times never go backwards in the file (arrivals on different threads may interleave by microseconds)."""
        self._last_log_time_ns = max(self._last_log_time_ns, log_time_ns)
        return self._last_log_time_ns

    def write_sample(self, sample: RecordedSample) -> None:
        """The bus's payload on the key's own channel, bytes untouched."""
        channel_id = self._raw_channels.get((sample.key, sample.encoding))
        if channel_id is None:
            mime, type_name = split_encoding(sample.encoding)
            schema_id = self._schema_id(type_name, "", b"") if type_name else 0
            channel_id = self._writer.register_channel(
                topic=sample.key,
                message_encoding=message_encoding_of(mime),
                schema_id=schema_id,
                metadata={RAW_KEY_METADATA: sample.key, ENCODING_METADATA: sample.encoding},
            )
            self._raw_channels[(sample.key, sample.encoding)] = channel_id
        log_time = self._log_time(sample.log_time_ns)
        self._writer.add_message(
            channel_id,
            log_time=log_time,
            data=sample.payload,
            publish_time=log_time,
            sequence=(sample.sequence or 0) & 0xFFFFFFFF,
        )
        self.raw_messages += 1

    def write_view(self, message: ViewMessage, log_time_ns: int) -> None:
        """A Foxglove-schema message (converted from a sample that arrived at ``log_time_ns``)."""
        channel_id = self._view_channels.get(message.topic)
        if channel_id is None:
            schema = message.schema
            schema_id = self._schema_id(schema.name, schema.encoding, schema.data)
            channel_id = self._writer.register_channel(
                topic=message.topic, message_encoding=schema.message_encoding, schema_id=schema_id
            )
            self._view_channels[message.topic] = channel_id
        log_time = self._log_time(log_time_ns)
        self._writer.add_message(channel_id, log_time=log_time, data=message.data, publish_time=log_time)
        self.view_messages += 1

    def add_metadata(self, name: str, values: dict[str, Any]) -> None:
        self._writer.add_metadata(name, {k: str(v) for k, v in values.items()})

    def add_attachment(self, name: str, media_type: str, data: bytes, log_time_ns: int) -> None:
        self._writer.add_attachment(
            create_time=log_time_ns, log_time=log_time_ns, name=name, media_type=media_type, data=data
        )

    def finish(self) -> None:
        """Write the summary section and close the file (idempotent)."""
        if self._finished:
            return
        self._finished = True
        self._writer.finish()
        if self._file is not None:
            self._file.close()
