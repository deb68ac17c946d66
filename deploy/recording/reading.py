"""Reading a zendock recording back: the bus's payloads in time order, its metadata and its world.

Raw channels are the ones whose metadata names a Zenoh key (see :mod:`deploy.recording.mcap_log`); the
Foxglove-schema channels are for viewers and are skipped here.
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import yaml
from mcap.exceptions import McapError
from mcap.reader import McapReader, make_reader
from mcap.summary import Summary

from deploy.recording.mcap_log import (
    ENCODING_METADATA,
    RAW_KEY_METADATA,
    RECORDING_METADATA,
    SUMMARY_METADATA,
    WORLD_ATTACHMENT,
)
from shared.config_errors import ConfigError
from shared.world import World, parse_world


@dataclass(frozen=True, slots=True)
class RawMessage:
    """One recorded sample: key, Zenoh encoding, payload, arrival time, publisher's number (0: none)."""

    key: str
    encoding: str
    type_name: str
    payload: bytes
    log_time_ns: int
    sequence: int


class Recording:
    """An open MCAP recording (use as a context manager)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        try:
            self._file: IO[bytes] = open(self.path, "rb")  # noqa: SIM115 - closed in close()
        except OSError as exc:
            raise ConfigError(f"{self.path}: cannot open recording: {exc.strerror or exc}") from None
        try:
            self._reader: McapReader = make_reader(self._file)
            summary = self._reader.get_summary()
        except (McapError, ValueError, EOFError) as exc:
            self._file.close()
            raise ConfigError(f"{self.path}: not a readable MCAP file ({exc})") from None
        if summary is None:
            self._file.close()
            raise ConfigError(f"{self.path}: the MCAP file has no summary (was the recording cut short?)")
        self._summary: Summary = summary

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._file.close()

    # --- channels ------------------------------------------------------------------------------------

    def raw_keys(self) -> dict[str, int]:
        """Recorded keys and how many messages each has."""
        counts: dict[str, int] = {}
        stats = self._summary.statistics
        for channel_id, channel in self._summary.channels.items():
            key = channel.metadata.get(RAW_KEY_METADATA)
            if key is not None:
                n = stats.channel_message_counts.get(channel_id, 0) if stats is not None else 0
                counts[key] = counts.get(key, 0) + n
        return counts

    def view_topics(self) -> dict[str, str]:
        """Foxglove-schema topics and their schema names."""
        out = {}
        for channel in self._summary.channels.values():
            if RAW_KEY_METADATA not in channel.metadata:
                schema = self._summary.schemas.get(channel.schema_id)
                out[channel.topic] = schema.name if schema is not None else ""
        return out

    def time_range_ns(self) -> tuple[int, int]:
        stats = self._summary.statistics
        if stats is None:
            return (0, 0)
        return (stats.message_start_time, stats.message_end_time)

    def raw_messages(self, keys: Sequence[str] | None = None) -> Iterator[RawMessage]:
        """The recorded samples in arrival order, optionally only those on ``keys``."""
        wanted = set(keys) if keys else None
        topics = [
            c.topic
            for c in self._summary.channels.values()
            if RAW_KEY_METADATA in c.metadata and (wanted is None or c.metadata[RAW_KEY_METADATA] in wanted)
        ]
        if not topics:
            return
        for schema, channel, message in self._reader.iter_messages(topics=topics, log_time_order=True):
            key = channel.metadata.get(RAW_KEY_METADATA)
            if key is None:
                continue
            yield RawMessage(
                key=key,
                encoding=channel.metadata.get(ENCODING_METADATA, ""),
                type_name=schema.name if schema is not None else "",
                payload=message.data,
                log_time_ns=message.log_time,
                sequence=message.sequence,
            )

    # --- metadata and attachments --------------------------------------------------------------------

    def metadata(self, name: str) -> dict[str, str]:
        for record in self._reader.iter_metadata():
            if record.name == name:
                return dict(record.metadata)
        return {}

    def recording_info(self) -> dict[str, str]:
        return self.metadata(RECORDING_METADATA)

    def summary(self) -> dict[str, Any]:
        """Per-key counts and losses as recorded (``{key: {received, lost, gaps, ...}}``)."""
        raw = self.metadata(SUMMARY_METADATA)
        return {k: json.loads(v) for k, v in raw.items() if v.startswith("{")}

    def world(self) -> World | None:
        """The world file attached at recording time, if any."""
        for attachment in self._reader.iter_attachments():
            if attachment.name == WORLD_ATTACHMENT:
                return parse_world(
                    yaml.safe_load(attachment.data.decode()), f"{self.path}:{WORLD_ATTACHMENT}"
                )
        return None
