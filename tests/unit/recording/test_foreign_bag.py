"""A ROS 2 bag recorded elsewhere: replay reads what zendock has messages for and names what it leaves out."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from deploy.commands.replay import open_recording


def _foreign_bag(path: Path) -> None:
    store = get_typestore(Stores.ROS2_JAZZY)
    with Writer(path, version=8, storage_plugin=StoragePlugin.MCAP) as writer:
        count = writer.add_connection("/count", "std_msgs/msg/Int32", typestore=store)
        clock = writer.add_connection("/clock", "rosgraph_msgs/msg/Clock", typestore=store)
        number = store.types["std_msgs/msg/Int32"]
        Clock = store.types["rosgraph_msgs/msg/Clock"]
        Time = store.types["builtin_interfaces/msg/Time"]
        writer.write(count, 1, store.serialize_cdr(number(data=7), "std_msgs/msg/Int32"))
        writer.write(
            clock, 2, store.serialize_cdr(Clock(clock=Time(sec=1, nanosec=0)), "rosgraph_msgs/msg/Clock")
        )


def test_a_foreign_bag_names_the_types_replay_leaves_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _foreign_bag(tmp_path / "bag")
    with open_recording(str(tmp_path / "bag")) as recording:
        keys = recording.raw_keys()
    assert list(keys) == ["clock"], keys
    assert "left out, no zendock message has the type: std_msgs/msg/Int32" in capsys.readouterr().err
