"""A minimal client of the Foxglove WebSocket protocol (``foxglove.websocket.v1``) for tests.

Speaks the protocol as Foxglove does: reads ``serverInfo`` and ``advertise``, subscribes to channels by
topic, and decodes binary message frames (opcode 1: subscription id, log time, payload) and time frames
(opcode 2). Spec: github.com/foxglove/ws-protocol, docs/spec.md.

Servers built on foxglove-sdk (and foxglove_bridge 3.x) accept the same protocol only under its newer
name ``foxglove.sdk.v1``; like current Foxglove and Lichtblick, the client offers both names and the
server picks one.
"""

from __future__ import annotations

import json
import struct
import time
from dataclasses import dataclass, field
from typing import Any

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect

SUBPROTOCOLS = ("foxglove.websocket.v1", "foxglove.sdk.v1")
OP_MESSAGE_DATA = 0x01
OP_TIME = 0x02
_MESSAGE_HEADER = struct.Struct("<BIQ")
_TIME = struct.Struct("<BQ")


@dataclass(frozen=True)
class ReceivedMessage:
    topic: str
    log_time_ns: int
    payload: bytes


@dataclass
class FoxgloveTestClient:
    """Connects, records what the server says, and collects messages of subscribed channels."""

    url: str
    server_info: dict[str, Any] = field(default_factory=dict)
    channels: dict[int, dict[str, Any]] = field(default_factory=dict)
    messages: list[ReceivedMessage] = field(default_factory=list)
    times_ns: list[int] = field(default_factory=list)
    _subscriptions: dict[int, str] = field(default_factory=dict)
    _ws: ClientConnection | None = None

    def __enter__(self) -> FoxgloveTestClient:
        self._ws = connect(
            self.url, subprotocols=list(SUBPROTOCOLS), open_timeout=10, max_size=None
        ).__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        if self._ws is not None:
            self._ws.close()

    @property
    def subprotocol(self) -> str | None:
        assert self._ws is not None
        return self._ws.subprotocol

    def topics(self) -> dict[str, dict[str, Any]]:
        return {c["topic"]: c for c in self.channels.values()}

    def subscribe(self, *topics: str) -> None:
        assert self._ws is not None
        by_topic = self.topics()
        subs = []
        for topic in topics:
            sub_id = len(self._subscriptions) + 1
            self._subscriptions[sub_id] = topic
            subs.append({"id": sub_id, "channelId": by_topic[topic]["id"]})
        self._ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    def pump_until(self, done, timeout_s: float) -> bool:  # type: ignore[no-untyped-def]
        """Read frames until ``done(self)`` is true or the timeout passes; returns ``done(self)``."""
        assert self._ws is not None
        deadline = time.monotonic() + timeout_s
        while not done(self):
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return bool(done(self))
            try:
                frame = self._ws.recv(timeout=min(remaining, 0.5))
            except TimeoutError:
                continue
            except ConnectionClosed:
                return bool(done(self))
            self._handle(frame)
        return True

    def _handle(self, frame: str | bytes) -> None:
        if isinstance(frame, str):
            op = json.loads(frame)
            if op.get("op") == "serverInfo":
                self.server_info = op
            elif op.get("op") == "advertise":
                for channel in op["channels"]:
                    self.channels[channel["id"]] = channel
            elif op.get("op") == "unadvertise":
                for channel_id in op["channelIds"]:
                    self.channels.pop(channel_id, None)
            return
        if frame[0] == OP_MESSAGE_DATA:
            _, sub_id, log_time = _MESSAGE_HEADER.unpack_from(frame)
            topic = self._subscriptions.get(sub_id, "?")
            self.messages.append(ReceivedMessage(topic, log_time, bytes(frame[_MESSAGE_HEADER.size :])))
        elif frame[0] == OP_TIME:
            self.times_ns.append(_TIME.unpack_from(frame)[1])

    def received(self, topic: str) -> list[ReceivedMessage]:
        return [m for m in self.messages if m.topic == topic]
