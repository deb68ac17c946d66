"""The live view as a process: a Foxglove WebSocket client sees the simulator's topics and the room."""

from __future__ import annotations

import time

import psutil
import zenoh

from shared.messages import Clock
from tests.support.bus import KeyRecorder
from tests.support.foxglove_client import SUBPROTOCOLS, FoxgloveTestClient
from tests.support.processes import REPO_ROOT, ServiceProcess, free_port, wait_until

GLASS_ROOM = str(REPO_ROOT / "deploy/worlds/glass_room.yaml")
#: The live view's memory budget.
MAX_RSS_MB = 100.0


def _connect(url: str, viz: ServiceProcess) -> FoxgloveTestClient:
    clients: list[FoxgloveTestClient] = []

    def connected() -> bool:
        assert viz.alive(), viz.output()[-2000:]
        try:
            clients.append(FoxgloveTestClient(url).__enter__())
        except OSError:
            return False
        return True

    wait_until(connected, 20.0, lambda: f"no WebSocket server at {url}: {viz.output()[-1500:]}")
    return clients[0]


def _subscribe_until_each_delivers(
    client: FoxgloveTestClient, topics: list[str], timeout_s: float = 20.0
) -> bool:
    """Subscribe to ``topics`` until each has delivered a message, or ``timeout_s``. The Foxglove server may
    advertise a channel a moment before it accepts subscriptions to it ("attempted to subscribe to unknown
    channel"): ask again for those still silent, as a viewer's user would."""
    deadline = time.monotonic() + timeout_s
    client.subscribe(*topics)
    while not client.pump_until(lambda c: all(c.received(t) for t in topics), 5.0):
        if time.monotonic() >= deadline:
            return False
        client.subscribe(*[t for t in topics if not client.received(t)])
    return True


def test_a_foxglove_client_sees_the_live_stack(spawn, bus: zenoh.Session, namespace: str) -> None:  # type: ignore[no-untyped-def]
    port = free_port()
    clock = KeyRecorder(bus, f"{namespace}/clock", Clock)
    spawn("simulator", "--world", GLASS_ROOM, "-p", "rtf=2")
    viz = spawn("viz", "--world", GLASS_ROOM, "--port", str(port))
    url = f"ws://127.0.0.1:{port}"
    ns = f"/{namespace}"
    wanted = {
        f"{ns}/scan": "foxglove.LaserScan",
        f"{ns}/tf": "foxglove.FrameTransforms",
        f"{ns}/ultrasonic": "foxglove.SceneUpdate",
        f"{ns}/world": "foxglove.SceneUpdate",
        f"{ns}/tf_static": "foxglove.FrameTransforms",
    }
    client = _connect(url, viz)
    try:
        assert client.subprotocol in SUBPROTOCOLS
        assert client.pump_until(lambda c: set(wanted) <= set(c.topics()), 20.0), sorted(client.topics())
        assert client.server_info["op"] == "serverInfo" and "time" in client.server_info["capabilities"]
        for topic, schema in wanted.items():
            channel = client.topics()[topic]
            assert (channel["schemaName"], channel["encoding"], channel["schemaEncoding"]) == (
                schema,
                "protobuf",
                "protobuf",
            ), channel
        assert _subscribe_until_each_delivers(client, list(wanted)), {
            t: len(client.received(t)) for t in wanted
        }
        assert client.pump_until(lambda c: bool(c.times_ns), 10.0), "no time broadcast from the live view"
        world = client.received(f"{ns}/world")[0].payload
        assert b"glass" in world and b"staging/home" in world  # latched: sent when the client subscribed
        scan = client.received(f"{ns}/scan")[-1]
        assert len(scan.payload) > 360 * 8 and scan.log_time_ns < 10**12  # stamped on the simulator's clock
        assert psutil.Process(viz.pid).memory_info().rss / 1e6 < MAX_RSS_MB
    finally:
        client.__exit__()

    # restarting the live view changes nothing for the others: the clock runs on, a new client sees it all
    viz.stop()
    seen = clock.count
    clock.wait_for(after=seen + 20, timeout_s=10.0)
    viz.start()
    client = _connect(url, viz)
    try:
        assert client.pump_until(lambda c: f"{ns}/scan" in c.topics(), 20.0)
    finally:
        client.__exit__()


def test_the_camera_is_rendered_only_while_a_viewer_watches_it(
    spawn, bus: zenoh.Session, namespace: str
) -> None:  # type: ignore[no-untyped-def]
    port = free_port()
    spawn("simulator", "--world", GLASS_ROOM, "-p", "rtf=1")
    viz = spawn("viz", "--world", GLASS_ROOM, "--port", str(port))
    camera = f"/{namespace}/camera/image_raw"
    client = _connect(f"ws://127.0.0.1:{port}", viz)
    try:
        assert client.pump_until(lambda c: camera in c.topics(), 20.0), sorted(client.topics())
        assert client.topics()[camera]["schemaName"] == "foxglove.RawImage"
        assert "subscribing" not in viz.output()  # advertised, but nothing asked of the bus yet
        assert _subscribe_until_each_delivers(client, [camera]), viz.output()[-1500:]
        frame = client.received(camera)[-1].payload
        assert len(frame) > 640 * 480 and b"mono8" in frame
    finally:
        client.__exit__()
    wait_until(lambda: "no viewer on" in viz.output(), 10.0, lambda: viz.output()[-1500:])


def test_a_fleet_is_shown_robot_by_robot_each_under_its_own_frames(spawn, namespace: str, tmp_path) -> None:  # type: ignore[no-untyped-def]
    world = tmp_path / "pair.yaml"
    world.write_text(
        "name: pair\nbounds: [0, 0, 6, 4]\ndocks:\n  - {id: d, pose: [0.6, 2.0, 3.14159]}\n"
        "robots:\n  - {name: r1, start: [2, 1, 0]}\n  - {name: r2, start: [4, 3, 3.14159]}\n"
    )
    port = free_port()
    spawn("simulator", "--world", str(world), "-p", "rtf=2")
    viz = spawn("viz", "--world", str(world), "--port", str(port), "-p", "robots=[r1, r2]")
    ns = f"/{namespace}"
    wanted = [
        f"{ns}/r1/scan",
        f"{ns}/r2/scan",
        f"{ns}/r1/tf",
        f"{ns}/r2/tf",
        f"{ns}/r1/robot",
        f"{ns}/r2/robot",
    ]
    client = _connect(f"ws://127.0.0.1:{port}", viz)
    try:
        assert client.pump_until(lambda c: set(wanted) <= set(c.topics()), 20.0), sorted(client.topics())
        # (Seen once in make test without asking again: r2/scan never came.)
        assert _subscribe_until_each_delivers(client, wanted), (
            {t: len(client.received(t)) for t in wanted},
            viz.output()[-1500:],
        )
        for robot in ("r1", "r2"):
            transforms = client.received(f"{ns}/{robot}/tf")[-1].payload
            assert f"{robot}/base_link".encode() in transforms and f"{robot}/odom".encode() in transforms
            assert (
                client.received(f"{ns}/{robot}/scan")[-1].payload.count(f"{robot}/lidar_link".encode()) == 1
            )
            assert f"{robot}/base_link".encode() in client.received(f"{ns}/{robot}/robot")[0].payload
    finally:
        client.__exit__()
