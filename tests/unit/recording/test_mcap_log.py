"""The MCAP layout: raw msgpack channels named by key and type, Foxglove channels, metadata, time order."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest
from mcap.reader import make_reader

from deploy.recording.mcap_log import ENCODING_METADATA, RAW_KEY_METADATA
from deploy.recording.reading import Recording
from deploy.recording.replay import remap_key, selected_keys
from shared.config_errors import ConfigError
from tests.unit.recording.synthetic import write_run


def test_raw_channels_keep_key_type_payload_and_number(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    samples = write_run(path)
    with Recording(path) as recording:
        raw = list(recording.raw_messages())
        assert Counter(m.key for m in raw) == Counter(s.key for s in samples)
        assert [m.payload for m in raw] == [s.payload for s in samples]
        assert [m.log_time_ns for m in raw] == sorted(m.log_time_ns for m in raw)
        sonar = [m for m in raw if m.key == "r1/ultrasonic"]
        assert sonar[0].type_name == "sensor_msgs/msg/Range"
        assert sonar[0].encoding == "application/msgpack;sensor_msgs/msg/Range"
        assert [m.sequence for m in sonar] == list(range(1, len(sonar) + 1))
        assert recording.world() is not None and recording.world().name == "seed_room"  # type: ignore[union-attr]
        views = recording.view_topics()
    assert views["/r1/ultrasonic"] == "foxglove.SceneUpdate"
    assert views["/r1/ground_truth_pose"] == "foxglove.PoseInFrame"
    assert views["/r1/battery_status"] == "zendock.BatteryStatus"


def test_the_file_follows_the_mcap_registry(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    write_run(path)
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    for channel in summary.channels.values():
        schema = summary.schemas.get(channel.schema_id)
        if RAW_KEY_METADATA in channel.metadata:
            assert channel.message_encoding == "msgpack"
            assert channel.metadata[ENCODING_METADATA].endswith(schema.name)  # type: ignore[union-attr]
            assert schema is not None and schema.encoding == "" and schema.data == b""
        else:
            assert channel.topic.startswith("/")
            assert (channel.message_encoding, schema.encoding) in {  # type: ignore[union-attr]
                ("protobuf", "protobuf"),
                ("json", "jsonschema"),
            }


def test_a_file_that_is_not_mcap_is_refused_by_name(tmp_path: Path) -> None:
    bogus = tmp_path / "bogus.mcap"
    bogus.write_bytes(b"not an mcap file at all")
    with pytest.raises(ConfigError, match="bogus.mcap"):
        Recording(bogus)


def test_replay_moves_keys_between_namespaces() -> None:
    assert remap_key("r1/scan", "r1", "r2") == "r2/scan"
    assert remap_key("r1/scan", "r1", None) == "r1/scan"
    assert remap_key("scan", "", "r2") == "r2/scan"
    assert remap_key("r1/scan", "r1", "") == "scan"


def test_replay_keys_may_be_given_relative_to_the_recording() -> None:
    recorded = ["r1/scan", "r1/tf", "r1/clock"]
    assert selected_keys(recorded, ["scan", "/r1/tf"], "r1") == ["r1/scan", "r1/tf"]
    assert selected_keys(recorded, [], "r1") == sorted(recorded)
    assert selected_keys(recorded, ["odom"], "r1") == []
