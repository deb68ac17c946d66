"""One recording from start to finish: subscribe, write until told to stop, account for every sample.

:func:`record` is what ``zendock record`` runs, callable with any Zenoh session (tests pass their own).
"""

from __future__ import annotations

import datetime as _dt
import socket
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import zenoh

from deploy.recording.mcap_log import RECORDING_METADATA, SUMMARY_METADATA, WORLD_ATTACHMENT, McapLog
from deploy.recording.recorder import BusRecorder, RecorderStats
from deploy.recording.summary import KeySummary, summarize, summary_metadata
from shared.foxglove_view import WORLD_VIEW_TOPIC, view_topic, world_scene
from shared.names import topic_key
from shared.world import load_world

if TYPE_CHECKING:  # rosbags loads only when a ROS 2 bag is written
    from deploy.recording.ros2_bag import Ros2BagLog

#: How often the wait for the end looks at the stop flag.
POLL_S = 0.1


@dataclass(frozen=True)
class RecordRequest:
    """What to record, where, and for how long (``duration_s`` None: until stopped)."""

    output: Path
    keys: tuple[str, ...] = ()
    duration_s: float | None = None
    world: Path | None = None
    views: bool = True
    compression: str = "zstd"
    #: ``zendock`` (msgpack payloads and Foxglove views in one MCAP file) or ``ros2`` (a ROS 2 bag directory).
    format: str = "zendock"


@dataclass
class RecordResult:
    path: Path
    duration_s: float
    rows: list[KeySummary]
    stats: RecorderStats
    view_messages: int
    #: Messages a ROS 2 bag could not carry (zendock's own types), by type.
    skipped: dict[str, int] = field(default_factory=dict)

    @property
    def lost(self) -> int:
        return sum(r.lost for r in self.rows)

    @property
    def received(self) -> int:
        return sum(r.received for r in self.rows)


def selectors_for(namespace: str, keys: tuple[str, ...]) -> list[str]:
    """Zenoh key expressions to subscribe: the given keys in the namespace, or everything in it."""
    if not keys:
        return [topic_key(namespace, "**")]
    return [topic_key(namespace, k) for k in keys]


def record(
    session: zenoh.Session,
    namespace: str,
    request: RecordRequest,
    stop: threading.Event,
    on_started: threading.Event | None = None,
) -> RecordResult:
    """Record until ``stop`` is set or ``duration_s`` has passed; the file is complete when this returns."""
    world = load_world(request.world) if request.world is not None else None
    selectors = selectors_for(namespace, request.keys)
    mcap_log: McapLog | Ros2BagLog
    if request.format == "ros2":
        from deploy.recording.ros2_bag import Ros2BagLog  # noqa: PLC0415 - rosbags only for ROS 2 bags

        mcap_log = Ros2BagLog(request.output, namespace)
    else:
        mcap_log = McapLog(request.output, compression=request.compression)
    started_ns = time.time_ns()
    mcap_log.add_metadata(
        RECORDING_METADATA,
        {
            "namespace": namespace,
            "selectors": ",".join(selectors),
            "started": _dt.datetime.now(_dt.UTC).isoformat(timespec="milliseconds"),
            "host": socket.gethostname(),
            "world": str(request.world) if request.world is not None else "",
        },
    )
    if world is not None and request.world is not None:
        mcap_log.add_attachment(
            WORLD_ATTACHMENT, "application/yaml", Path(request.world).read_bytes(), started_ns
        )
        if request.views:
            topic = view_topic(namespace, WORLD_VIEW_TOPIC)
            mcap_log.write_view(world_scene(topic, world, started_ns), started_ns)
    recorder = BusRecorder(session, selectors, mcap_log, views=request.views)
    started = time.monotonic()
    if on_started is not None:
        on_started.set()
    try:
        while not stop.is_set():
            if request.duration_s is not None and time.monotonic() - started >= request.duration_s:
                break
            stop.wait(POLL_S)
    finally:
        recorder.stop()
        duration_s = time.monotonic() - started
        rows = summarize(recorder.tracker, recorder.type_of)
        mcap_log.add_metadata(SUMMARY_METADATA, summary_metadata(rows, duration_s))
        mcap_log.finish()
    skipped = {} if isinstance(mcap_log, McapLog) else dict(mcap_log.skipped)
    return RecordResult(request.output, duration_s, rows, recorder.stats, mcap_log.view_messages, skipped)
