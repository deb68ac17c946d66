"""Replaying a recording onto the bus with its original timing (the ``ros2 bag play`` role).

Each recorded key gets a publisher with the recorded Zenoh encoding (``application/msgpack;<type>``), a
fresh sequence number on every sample (a replay is a new publisher, so receivers count its samples as
they count any other's; the attachment also names the publisher) and a liveliness token, so
``zendock keys list`` shows the replay. Samples go out reliably and block rather than drop: a replay
is a test input, it must arrive whole. Timing follows the recorded arrival times, scaled by ``rate``;
``loop`` starts over at the end.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import zenoh

from deploy.recording.reading import RawMessage, Recording
from shared.names import endpoint_token_key, normalise_namespace, topic_key
from shared.node import publisher_gid, sequence_attachment

if TYPE_CHECKING:  # rosbags loads only when a ROS 2 bag is replayed
    from deploy.recording.ros2_bag import Ros2BagRecording

REPLAY_NODE_NAME = "replay"
#: Waits longer than this are split so a stop request is noticed quickly.
MAX_WAIT_S = 0.1


def remap_key(key: str, recorded_namespace: str, namespace: str | None) -> str:
    """The key a recorded sample is replayed on: moved from the recording's namespace to ``namespace``."""
    if namespace is None:
        return key
    recorded = normalise_namespace(recorded_namespace)
    relative = key[len(recorded) + 1 :] if recorded and key.startswith(recorded + "/") else key
    return topic_key(namespace, relative)


def selected_keys(recorded: Sequence[str], wanted: Sequence[str], recorded_namespace: str) -> list[str]:
    """The recorded keys a ``--keys`` list names (as full keys or relative to the recording's namespace)."""
    if not wanted:
        return sorted(recorded)
    names = {w.strip("/") for w in wanted}
    names |= {topic_key(recorded_namespace, w) for w in wanted}
    return sorted(k for k in recorded if k in names)


@dataclass
class ReplayStats:
    published: int = 0
    passes: int = 0
    per_key: dict[str, int] = field(default_factory=dict)


class _KeyPublisher:
    def __init__(
        self, session: zenoh.Session, key: str, encoding: str, type_name: str, namespace: str
    ) -> None:
        self._publisher = session.declare_publisher(
            key,
            encoding=zenoh.Encoding(encoding) if encoding else zenoh.Encoding.ZENOH_BYTES,
            reliability=zenoh.Reliability.RELIABLE,
            congestion_control=zenoh.CongestionControl.BLOCK,
        )
        self._token = session.liveliness().declare_token(
            endpoint_token_key("pub", namespace, REPLAY_NODE_NAME, type_name, key)
        )
        self._sequence = 0
        self._gid = publisher_gid(self._publisher.id)

    def put(self, payload: bytes) -> None:
        self._sequence += 1
        self._publisher.put(payload, attachment=sequence_attachment(self._sequence, self._gid))

    def close(self) -> None:
        self._token.undeclare()
        self._publisher.undeclare()


class Replayer:
    """Publishes a recording's samples on ``session``; :meth:`run` blocks until done or :meth:`stop`."""

    def __init__(
        self,
        session: zenoh.Session,
        recording: Recording | Ros2BagRecording,
        *,
        rate: float = 1.0,
        loop: bool = False,
        keys: Sequence[str] = (),
        namespace: str | None = None,
        on_message: Callable[[str, RawMessage], None] | None = None,
    ) -> None:
        if not rate > 0:
            raise ValueError(f"rate must be positive, got {rate}")
        self._session = session
        self._recording = recording
        self._rate = rate
        self._loop = loop
        recorded_namespace = recording.recording_info().get("namespace", "")
        self.keys = selected_keys(list(recording.raw_keys()), keys, recorded_namespace)
        self._recorded_namespace = recorded_namespace
        self._namespace = None if namespace is None else normalise_namespace(namespace)
        self._on_message = on_message
        self._stop = threading.Event()
        self._publishers: dict[tuple[str, str], _KeyPublisher] = {}
        self.stats = ReplayStats()

    def stop(self) -> None:
        """Ask :meth:`run` to return (from any thread or a signal handler)."""
        self._stop.set()

    def _publisher(self, key: str, message: RawMessage) -> _KeyPublisher:
        publisher = self._publishers.get((key, message.encoding))
        if publisher is None:
            namespace = self._namespace if self._namespace is not None else self._recorded_namespace
            publisher = _KeyPublisher(self._session, key, message.encoding, message.type_name, namespace)
            self._publishers[(key, message.encoding)] = publisher
        return publisher

    def _wait_until(self, deadline: float) -> bool:
        """Sleep until the monotonic ``deadline``; False when stopped meanwhile."""
        while not self._stop.is_set():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return True
            self._stop.wait(min(remaining, MAX_WAIT_S))
        return False

    def run(self) -> ReplayStats:
        try:
            if not self.keys:
                return self.stats
            while not self._stop.is_set():
                if not self._play_once():
                    break
                self.stats.passes += 1
                if not self._loop:
                    break
        finally:
            for publisher in self._publishers.values():
                publisher.close()
            self._publishers.clear()
        return self.stats

    def _play_once(self) -> bool:
        first_ns: int | None = None
        start = time.monotonic()
        for message in self._recording.raw_messages(self.keys):
            if first_ns is None:
                first_ns = message.log_time_ns
            if not self._wait_until(start + (message.log_time_ns - first_ns) / 1e9 / self._rate):
                return False
            key = remap_key(message.key, self._recorded_namespace, self._namespace)
            self._publisher(key, message).put(message.payload)
            self.stats.published += 1
            self.stats.per_key[key] = self.stats.per_key.get(key, 0) + 1
            if self._on_message is not None:
                self._on_message(key, message)
        return True
