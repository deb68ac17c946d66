"""Recording the bus: Zenoh samples into an MCAP file, with losses counted from sequence numbers.

Zenoh's receiving thread never runs Python here: each subscription hands samples to a Zenoh FIFO channel
(Rust side, :data:`FIFO_CAPACITY` deep), so a busy interpreter never slows the transport down, which
for best-effort streams would mean drops. One reader thread per subscription copies samples out into an
unbounded queue; one writer thread takes them in order, counts them per publisher
(:mod:`deploy.recording.sequence`), writes the payload and, when the key has a Foxglove view, the
converted message. Publisher counts per key come from the graph's liveliness tokens.

Log time: the Zenoh timestamp the router put on the sample (its arrival at the router), else the moment
the reader took it.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import zenoh

from deploy.recording.mcap_log import McapLog, RecordedSample, split_encoding
from deploy.recording.sequence import SequenceTracker
from shared.foxglove_view import convert_key
from shared.names import GRAPH_PREFIX, parse_token_key
from shared.node import publisher_id, sequence_number
from shared.schema import MessageError

if TYPE_CHECKING:  # rosbags loads only when a ROS 2 bag is written
    from deploy.recording.ros2_bag import Ros2BagLog

log = logging.getLogger(__name__)

_STOP = object()
PUBLISHER_TOKENS = f"{GRAPH_PREFIX}/pub/**"
#: Samples Zenoh may hold for a subscription before it waits for the reader (a burst of ~a minute at full stack rate).
FIFO_CAPACITY = 50_000


@dataclass
class RecorderStats:
    """What the writer thread has done so far (read from any thread: plain counters)."""

    written: int = 0
    views_written: int = 0
    view_errors: int = 0
    max_backlog: int = 0


class _WallClock:
    """Nanoseconds since the epoch that never go backwards (monotonic, anchored once to the wall clock)."""

    def __init__(self) -> None:
        self._wall0 = time.time_ns()
        self._mono0 = time.monotonic_ns()

    def now_ns(self) -> int:
        return self._wall0 + (time.monotonic_ns() - self._mono0)


class PublisherCounts:
    """How many zendock publishers each key has, kept current from liveliness tokens."""

    def __init__(self, session: zenoh.Session, timeout_s: float = 1.0) -> None:
        self._lock = threading.Lock()
        self._tokens: dict[str, set[str]] = {}
        self._subscriber = session.liveliness().declare_subscriber(PUBLISHER_TOKENS, self._on_token)
        for reply in session.liveliness().get(PUBLISHER_TOKENS, timeout=timeout_s):
            if reply.ok is not None:
                self._add(str(reply.ok.key_expr))

    def _add(self, token: str) -> None:
        entry = parse_token_key(token)
        if entry is not None and entry.kind == "pub":
            with self._lock:
                self._tokens.setdefault(entry.key, set()).add(token)

    def _on_token(self, sample: zenoh.Sample) -> None:
        token = str(sample.key_expr)
        if sample.kind == zenoh.SampleKind.PUT:
            self._add(token)
            return
        entry = parse_token_key(token)
        if entry is not None:
            with self._lock:
                self._tokens.get(entry.key, set()).discard(token)

    def on(self, key: str) -> int:
        with self._lock:
            return len(self._tokens.get(key, ()))

    def close(self) -> None:
        self._subscriber.undeclare()


class BusRecorder:
    """Records ``selectors`` (Zenoh key expressions) into ``mcap_log`` until :meth:`stop`.

    ``views``: also write the Foxglove-schema channels (conversion runs on the writer thread).
    """

    def __init__(
        self,
        session: zenoh.Session,
        selectors: Sequence[str],
        mcap_log: McapLog | Ros2BagLog,
        views: bool = True,
    ) -> None:
        self._log = mcap_log
        self._views = views
        self._clock = _WallClock()
        self._queue: queue.SimpleQueue[object] = queue.SimpleQueue()
        self.stats = RecorderStats()
        self._publishers = PublisherCounts(session)
        self.tracker = SequenceTracker(self._publishers.on)
        self._types: dict[str, str] = {}
        self._writer_error: BaseException | None = None
        self._thread = threading.Thread(target=self._write_loop, name="mcap-writer", daemon=True)
        self._thread.start()
        self._subscribers = [
            session.declare_subscriber(selector, zenoh.handlers.FifoChannel(FIFO_CAPACITY))
            for selector in selectors
        ]
        self._readers = [
            threading.Thread(
                target=self._read_loop, args=(sub.handler,), name=f"zenoh-reader-{i}", daemon=True
            )
            for i, sub in enumerate(self._subscribers)
        ]
        for reader in self._readers:
            reader.start()

    # --- reader threads: copy out of Zenoh's FIFO and enqueue, nothing else ----------------------------

    def _read_loop(self, fifo: zenoh.handlers.Handler[zenoh.Sample]) -> None:
        """Receives from the subscription's FIFO (not the subscriber, which ``stop`` must be free to undeclare)."""
        while True:
            try:
                sample = fifo.recv()
            except zenoh.ZError:  # the subscriber was undeclared and the FIFO is drained: the recording ends
                return
            if sample.kind != zenoh.SampleKind.PUT:
                continue
            stamp = sample.timestamp
            arrived = stamp.get_time_as_ntp64().as_nanos() if stamp is not None else self._clock.now_ns()
            attachment = sample.attachment
            self._queue.put(
                (
                    str(sample.key_expr),
                    str(sample.encoding),
                    sample.payload.to_bytes(),
                    attachment.to_bytes() if attachment is not None else None,
                    arrived,
                )
            )

    # --- the writer thread ---------------------------------------------------------------------------

    def _write_loop(self) -> None:
        try:
            while True:
                item = self._queue.get()
                if item is _STOP:
                    return
                backlog = self._queue.qsize()
                if backlog > self.stats.max_backlog:
                    self.stats.max_backlog = backlog
                self._write(item)  # type: ignore[arg-type]
        except BaseException as exc:  # a full disk: keep the error for stop() to raise
            self._writer_error = exc
            log.error("recording failed: %s", exc)

    def _write(self, item: tuple[str, str, bytes, bytes | None, int]) -> None:
        key, encoding, payload, attachment, arrived_ns = item
        sequence = sequence_number(attachment)
        self.tracker.feed(key, sequence, publisher_id(attachment), arrived_ns / 1e9)
        self._log.write_sample(RecordedSample(key, encoding, payload, arrived_ns, sequence))
        self.stats.written += 1
        _, type_name = split_encoding(encoding)
        if type_name:
            self._types[key] = type_name
        if not self._views:
            return
        try:
            views = convert_key(key, type_name, payload)
        except MessageError:
            self.stats.view_errors += 1
            return
        for view in views:
            self._log.write_view(view, arrived_ns)
            self.stats.views_written += 1

    # --- control -------------------------------------------------------------------------------------

    def type_of(self, key: str) -> str:
        return self._types.get(key, "")

    def stop(self) -> None:
        """Stop listening, write everything still queued, and wait for the writer."""
        for subscriber in self._subscribers:
            subscriber.undeclare()
        for reader in self._readers:
            reader.join()
        self._subscribers.clear()
        self._publishers.close()
        self._queue.put(_STOP)
        self._thread.join()
        if self._writer_error is not None:
            raise self._writer_error
