"""The Foxglove WebSocket side of the bridge: channels made on first use, latched topics replayed to late viewers.

Built on ``foxglove-sdk``'s server (the ``foxglove.websocket.v1`` protocol that Foxglove and Lichtblick
speak), in its own :class:`foxglove.Context` so nothing else in the process logs to it. The server runs
its own threads: its listener only hands "a client subscribed to topic T" to the ``on_subscribe`` hook;
the caller decides on which thread to act on it. Everything else here is called from one thread at a time
(the node's callbacks), so it needs no locks. No Zenoh in here.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import foxglove
from foxglove.websocket import Capability, ChannelView, Client, ServerListener

from shared.foxglove_view import ViewMessage
from shared.foxglove_view.encoding import ViewSchema

log = logging.getLogger(__name__)


class _Listener(ServerListener):
    """Hands subscriptions to the hook and logs client activity (runs on the server's threads)."""

    def __init__(self, on_subscribe: Callable[[str], None]) -> None:
        self._on_subscribe = on_subscribe

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        log.debug("client %d subscribed to %s", client.id, channel.topic)
        self._on_subscribe(channel.topic)

    def on_unsubscribe(self, client: Client, channel: ChannelView) -> None:
        log.debug("client %d unsubscribed from %s", client.id, channel.topic)


class LiveView:
    """A Foxglove WebSocket server fed with :class:`ViewMessage` s.

    ``now_ns`` gives the log time for messages without a stamp of their own (and for replays of latched
    messages), on the same clock as the stamps: sim time when the robot runs on it.
    """

    def __init__(
        self,
        host: str,
        port: int,
        now_ns: Callable[[], int],
        on_subscribe: Callable[[str], None],
        name: str = "zendock",
    ) -> None:
        self._now_ns = now_ns
        self._context = foxglove.Context()
        self._channels: dict[str, foxglove.Channel] = {}
        self._latched: dict[str, ViewMessage] = {}
        self._sources: dict[str, set[str]] = {}
        self.sent = 0
        self._server = foxglove.start_server(
            name=name,
            host=host,
            port=port,
            capabilities=[Capability.Time],
            server_listener=_Listener(on_subscribe),
            context=self._context,
        )

    @property
    def port(self) -> int:
        return int(self._server.port)

    def wants(self, source: str) -> bool:
        """Whether converting ``source``'s next message is worth it: a viewer listens, or it is not yet advertised."""
        outputs = self._sources.get(source)
        if not outputs:
            return True
        return any(self._channels[topic].has_sinks() for topic in outputs)

    def publish(self, source: str, messages: list[ViewMessage], latched: bool = False) -> None:
        """Log ``messages`` (converted from ``source``); a latched topic's latest is kept for late viewers."""
        for message in messages:
            self._sources.setdefault(source, set()).add(message.topic)
            if latched:
                self._latched[message.topic] = message
            self._log(message, message.stamp_ns or self._now_ns())

    def replay_latched(self, topic: str) -> None:
        """Send a latched topic's latest message again (a viewer just subscribed), stamped now."""
        message = self._latched.get(topic)
        if message is not None:
            self._log(message, self._now_ns())

    def broadcast_time(self, now_ns: int) -> None:
        """Tell viewers the robot's time (so a sim-time run shows sim time on their timeline)."""
        self._server.broadcast_time(now_ns)

    def advertise(self, topic: str, schema: ViewSchema) -> None:
        """Offer ``topic`` before any message exists (an on-demand stream starts when someone subscribes)."""
        self._channel(topic, schema)

    def has_viewer(self, topic: str) -> bool:
        channel = self._channels.get(topic)
        return channel is not None and channel.has_sinks()

    def _channel(self, topic: str, schema: ViewSchema) -> foxglove.Channel:
        channel = self._channels.get(topic)
        if channel is None:
            channel = foxglove.Channel(
                topic,
                schema=foxglove.Schema(name=schema.name, encoding=schema.encoding, data=schema.data),
                message_encoding=schema.message_encoding,
                context=self._context,
            )
            self._channels[topic] = channel
            log.info("advertising %s (%s)", topic, schema.name)
        return channel

    def _log(self, message: ViewMessage, log_time_ns: int) -> None:
        channel = self._channel(message.topic, message.schema)
        channel.log(message.data, log_time=max(0, log_time_ns))
        self.sent += 1

    def close(self) -> None:
        self._server.stop()
        for channel in self._channels.values():
            channel.close()
        self._channels.clear()
