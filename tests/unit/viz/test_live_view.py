"""The Foxglove side of the live view, without a bus: channels appear, messages flow, latched ones replay."""

from __future__ import annotations

import threading

from services.viz.live_view import LiveView
from shared.foxglove_view.encoding import json_schema, json_view
from tests.support.foxglove_client import SUBPROTOCOLS, FoxgloveTestClient
from tests.support.processes import free_port

SCHEMA = json_schema("test.Reading", {"value": {"type": "number"}})


def test_viewers_see_channels_and_latched_messages_replayed_on_subscribe() -> None:
    subscribed: list[str] = []
    event = threading.Event()

    def on_subscribe(topic: str) -> None:
        subscribed.append(topic)
        event.set()

    view = LiveView("127.0.0.1", free_port(), now_ns=lambda: 42, on_subscribe=on_subscribe)
    try:
        view.publish("map", [json_view("/map", SCHEMA, {"value": 1.0}, stamp_ns=7)], latched=True)
        view.publish("scan", [json_view("/scan", SCHEMA, {"value": 2.0})])
        with FoxgloveTestClient(f"ws://127.0.0.1:{view.port}") as client:
            assert client.subprotocol in SUBPROTOCOLS
            assert client.pump_until(lambda c: {"/map", "/scan"} <= set(c.topics()), 10.0), client.topics()
            assert client.server_info["op"] == "serverInfo" and "time" in client.server_info["capabilities"]
            channel = client.topics()["/map"]
            assert (channel["encoding"], channel["schemaName"]) == ("json", "test.Reading")
            client.subscribe("/map", "/scan")
            assert event.wait(10.0) and "/map" in subscribed
            view.replay_latched("/map")  # what the node does on the executor after on_subscribe
            assert client.pump_until(lambda c: c.received("/map"), 10.0)
            (message,) = client.received("/map")
            assert message.payload == b'{"value":1.0}' and message.log_time_ns == 42
            assert view.wants("scan")  # a viewer listens now
            view.publish("scan", [json_view("/scan", SCHEMA, {"value": 3.0})])
            assert client.pump_until(lambda c: c.received("/scan"), 10.0)
            view.broadcast_time(1_000_000_000)
            assert client.pump_until(lambda c: 1_000_000_000 in c.times_ns, 10.0)
    finally:
        view.close()


def test_an_unwatched_stream_is_not_worth_converting_once_advertised() -> None:
    view = LiveView("127.0.0.1", free_port(), now_ns=lambda: 0, on_subscribe=lambda _t: None)
    try:
        assert view.wants("scan")  # not advertised yet: convert once so viewers can see it exists
        view.publish("scan", [json_view("/scan", SCHEMA, {"value": 2.0})])
        assert not view.wants("scan")
    finally:
        view.close()
