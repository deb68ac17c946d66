"""Record a live simulator into MCAP, read it back, and replay it exactly into a fresh bus.

Losses: the recorder must miss nothing that reached the bus. A sender under CPU pressure may itself drop
a sample (zendock's state topics use Zenoh's drop-on-congestion), so the test compares the recording
with an independent subscriber on its own session: every number that subscriber saw, the file has, and
the recorder's own account of gaps matches the numbers missing from the file.
"""

from __future__ import annotations

import threading
from collections import defaultdict
from pathlib import Path

import zenoh
from mcap.reader import make_reader

from deploy.recording.mcap_log import RAW_KEY_METADATA
from deploy.recording.reading import Recording
from deploy.recording.replay import Replayer
from deploy.recording.session import RecordRequest, record
from shared.messages import BatteryState, Clock
from shared.node import sequence_number
from shared.session import SessionSpec, open_session
from tests.support.bus import KeyRecorder
from tests.support.processes import REPO_ROOT, free_port, wait_until

GLASS_ROOM = REPO_ROOT / "deploy/worlds/glass_room.yaml"
RECORD_S = 3.0
EXPECTED_KEYS = (
    "clock",
    "tf",
    "tf_static",
    "odom",
    "scan",
    "ultrasonic",
    "dock_contact",
    "ground_truth_pose",
    "battery_status",
)
EXPECTED_VIEWS = {
    "scan": "foxglove.LaserScan",
    "tf": "foxglove.FrameTransforms",
    "ultrasonic": "foxglove.SceneUpdate",
    "world": "foxglove.SceneUpdate",
    "battery_status": "zendock.BatteryStatus",
}


def test_record_a_live_stack_then_replay_it_exactly(
    spawn,
    bus: zenoh.Session,
    namespace: str,  # type: ignore[no-untyped-def]
    router_endpoint: str,
    tmp_path: Path,
) -> None:
    clock = KeyRecorder(bus, f"{namespace}/clock", Clock)
    battery = KeyRecorder(bus, f"{namespace}/battery_status", BatteryState)
    spawn("simulator", "--world", str(GLASS_ROOM), "-p", "rtf=2")
    spawn("battery", "-p", "use_sim_time=true")
    clock.wait_for(timeout_s=20.0)
    battery.wait_for(timeout_s=20.0)
    path = tmp_path / "run.mcap"
    witnessed: dict[str, set[int]] = defaultdict(set)

    def witness(sample: zenoh.Sample) -> None:
        if sample.attachment is not None:
            witnessed[str(sample.key_expr)].add(sequence_number(sample.attachment))

    clock.close()
    battery.close()
    # the recorder gets a session of its own, as ``zendock record`` does: no other callbacks on its link
    with (
        open_session(SessionSpec(mode="client", connect=(router_endpoint,))) as recorder_session,
        open_session(SessionSpec(mode="client", connect=(router_endpoint,))) as other,
    ):
        # The state and sensor keys, not the camera: its images (300 kB at 15 Hz) keep the recorder's
        # interpreter busy enough that its session falls behind and the router drops best-effort samples
        # for it (measured; see the README's recording notes).
        witnesses = [other.declare_subscriber(f"{namespace}/{k}", witness) for k in EXPECTED_KEYS]
        result = record(
            recorder_session,
            namespace,
            RecordRequest(path, keys=EXPECTED_KEYS, duration_s=RECORD_S, world=GLASS_ROOM),
            threading.Event(),
        )
        for subscriber in witnesses:
            subscriber.undeclare()

    by_key = {row.key: row for row in result.rows}
    assert {f"{namespace}/{k}" for k in EXPECTED_KEYS} <= set(by_key), sorted(by_key)
    assert by_key[f"{namespace}/clock"].received >= 20 * RECORD_S  # 40 Hz (20 Hz at rtf 2), on a busy machine

    # read back with the mcap reader: channels, counts equal to the publishers' number ranges, time order
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None
        sequences: dict[str, list[int]] = defaultdict(list)
        view_counts: dict[str, int] = defaultdict(int)
        last_log_time = 0
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert message.log_time >= last_log_time, "the file is not in time order"
            last_log_time = message.log_time
            if RAW_KEY_METADATA in channel.metadata:
                assert channel.message_encoding == "msgpack" and schema is not None
                assert channel.metadata["zenoh_encoding"] == f"application/msgpack;{schema.name}"
                sequences[channel.topic].append(message.sequence)
            else:
                view_counts[channel.topic] += 1
                assert schema is not None
    for key, numbers in sequences.items():
        assert numbers == sorted(numbers), f"{key}: numbers out of order"
        window = set(range(numbers[0], numbers[-1] + 1))
        missing = window - set(numbers)
        assert not (witnessed[key] & missing), (
            f"{key}: the recorder missed {sorted(witnessed[key] & missing)}"
        )
        assert len(numbers) == by_key[key].received and len(missing) == by_key[key].lost
    view_schemas = {
        c.topic: summary.schemas[c.schema_id].name
        for c in summary.channels.values()
        if RAW_KEY_METADATA not in c.metadata
    }
    for topic, schema_name in EXPECTED_VIEWS.items():
        assert view_schemas[f"/{namespace}/{topic}"] == schema_name
    assert view_counts[f"/{namespace}/scan"] == len(sequences[f"{namespace}/scan"])

    # replay into a fresh bus, moved to another namespace: same payloads, same order, same types
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    received: dict[str, list[tuple[bytes, str, int]]] = defaultdict(list)
    with (
        open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))),
        open_session(SessionSpec(mode="client", connect=(endpoint,))) as player,
        open_session(SessionSpec(mode="client", connect=(endpoint,))) as listener,
    ):
        lock = threading.Lock()

        def on_sample(sample: zenoh.Sample) -> None:
            seq = sequence_number(sample.attachment) or 0
            with lock:
                received[str(sample.key_expr)].append((sample.payload.to_bytes(), str(sample.encoding), seq))

        subscriber = listener.declare_subscriber("replayed/**", on_sample)
        # Declared after it: once the player reaches this one, it reaches the subscriber above too.
        probed = threading.Event()
        probe = listener.declare_subscriber("probe/route", lambda _s: probed.set())

        def route_up() -> bool:
            player.put("probe/route", b"")
            return probed.wait(0.05)

        wait_until(route_up, 10.0, "the player never reached the listener")
        probe.undeclare()
        with Recording(path) as recording:
            recorded = defaultdict(list)
            for message in recording.raw_messages():
                recorded[message.key.replace(namespace, "replayed", 1)].append(
                    (message.payload, message.encoding)
                )
            replayer = Replayer(player, recording, rate=4.0, namespace="replayed")
            stats = replayer.run()
        total = sum(len(v) for v in recorded.values())
        assert stats.published == total
        wait_until(
            lambda: sum(len(v) for v in received.values()) >= total,
            10.0,
            lambda: f"{sum(len(v) for v in received.values())} of {total} replayed samples arrived",
        )
        subscriber.undeclare()
    assert set(received) == set(recorded)
    for key, samples in recorded.items():
        assert [(p, e) for p, e, _ in received[key]] == samples, f"{key}: replayed payloads differ"
        assert [s for _, _, s in received[key]] == list(range(1, len(samples) + 1))


def test_a_ros2_bag_reads_in_rosbags_with_the_same_messages_and_replays(
    spawn,
    bus: zenoh.Session,  # type: ignore[no-untyped-def]
    namespace: str,
    router_endpoint: str,
    tmp_path: Path,
) -> None:
    """``zendock record --format ros2``: a rosbag2 directory rosbags reads with its own Jazzy types."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    from deploy.recording.ros2_bag import Ros2BagRecording

    battery = KeyRecorder(bus, f"{namespace}/battery_status", BatteryState, keep=100_000)
    clock = KeyRecorder(bus, f"{namespace}/clock", Clock, keep=100_000)
    spawn("simulator", "--world", str(GLASS_ROOM), "-p", "rtf=2")
    spawn("battery", "-p", "use_sim_time=true")
    battery.wait_for(timeout_s=20.0)
    path = tmp_path / "bag"
    with open_session(SessionSpec(mode="client", connect=(router_endpoint,))) as recorder_session:
        result = record(
            recorder_session,
            namespace,
            RecordRequest(path, duration_s=RECORD_S, format="ros2"),
            threading.Event(),
        )
    assert (path / "metadata.yaml").is_file() and list(path.glob("*.mcap")), sorted(path.iterdir())
    assert "zendock_msgs/msg/DockContact" in result.skipped  # zendock's own type: no ROS 2 definition

    jazzy = get_typestore(Stores.ROS2_JAZZY)
    with Reader(path) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        assert topics["/battery_status"] == "sensor_msgs/msg/BatteryState"
        assert (
            topics["/scan"] == "sensor_msgs/msg/LaserScan" and topics["/clock"] == "rosgraph_msgs/msg/Clock"
        )
        stamps = {(m.header.stamp.sec, m.header.stamp.nanosec): m for m in battery.messages}
        bag_battery = [
            jazzy.deserialize_cdr(data, "sensor_msgs/msg/BatteryState")
            for c, _t, data in reader.messages(
                connections=[c for c in reader.connections if c.topic == "/battery_status"]
            )
        ]
    assert bag_battery
    for msg in bag_battery:
        ours = stamps[(msg.header.stamp.sec, msg.header.stamp.nanosec)]
        assert (
            abs(msg.percentage - ours.percentage) < 1e-6
            and msg.power_supply_status == ours.power_supply_status
        )

    # zendock replay plays the bag back as zendock messages, into another namespace
    target = f"{namespace}_replay"
    replayed = KeyRecorder(bus, f"{target}/battery_status", BatteryState)
    with Ros2BagRecording(path) as bag:
        assert bag.recording_info()["namespace"] == namespace
        assert bag.raw_keys()[f"{namespace}/battery_status"] == len(bag_battery)
        stats = Replayer(bus, bag, rate=20.0, keys=["battery_status"], namespace=target).run()
    assert stats.published == len(bag_battery)
    first = replayed.wait_for(timeout_s=10.0)
    assert (first.header.stamp.sec, first.header.stamp.nanosec) in stamps
    clock.close()
