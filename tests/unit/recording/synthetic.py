"""A small recorded run, written without a bus: a robot driving towards a wall with its sonar on."""

from __future__ import annotations

import math
from pathlib import Path

from deploy.recording.mcap_log import RECORDING_METADATA, WORLD_ATTACHMENT, McapLog, RecordedSample
from shared import messages
from shared.foxglove_view import convert_key
from shared.geometry import Pose2D
from shared.messages import (
    BatteryState,
    Header,
    Pose,
    PoseStamped,
    Range,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
)
from shared.node import encoding_for
from shared.schema import Message
from tests.support.processes import REPO_ROOT

SEED_ROOM = REPO_ROOT / "deploy/worlds/seed_room.yaml"
START_NS = 1_700_000_000_000_000_000
SONAR_MOUNT_X_M = 0.2
WALL_Y_M = 0.43  # the seed room's south wall


def _sample(key: str, msg: Message, t_s: float, seq: int) -> RecordedSample:
    return RecordedSample(key, str(encoding_for(msg.TYPE_NAME)), msg.encode(), START_NS + int(t_s * 1e9), seq)


def write_run(path: Path, namespace: str = "r1", steps: int = 50) -> list[RecordedSample]:
    """Drives from (0, 3) straight south at 0.5 m/s; the sonar looks ahead at the south wall."""
    samples: list[RecordedSample] = []
    ns = f"{namespace}/" if namespace else ""
    mount = TransformStamped(
        Header.at(0.0, "base_link"),
        "ultrasonic_link",
        Transform.from_pose2d(Pose2D(SONAR_MOUNT_X_M, 0.0, 0.0)),
    )
    samples.append(_sample(f"{ns}tf_static", TFMessage([mount]), 0.0, 1))
    plan = messages.Path(
        Header.at(0.0, "map"),
        [PoseStamped(Header.at(0.0, "map"), Pose.from_pose2d(Pose2D(0.0, y, 0.0))) for y in (3.0, 2.0, 1.0)],
    )
    samples.append(_sample(f"{ns}plan", plan, 0.01, 1))
    for i in range(steps):
        t = 0.02 + i * 0.05
        pose = Pose2D(0.0, 3.0 - 0.5 * i * 0.05, -math.pi / 2)
        samples.append(
            _sample(
                f"{ns}ground_truth_pose", PoseStamped(Header.at(t, "map"), Pose.from_pose2d(pose)), t, i + 1
            )
        )
        distance = pose.y - SONAR_MOUNT_X_M - WALL_Y_M
        sonar = Range(Header(Time.from_sec(t), "ultrasonic_link"), Range.ULTRASOUND, 0.5, 0.02, 3.0, distance)
        samples.append(_sample(f"{ns}ultrasonic", sonar, t + 0.001, i + 1))
        battery = BatteryState(header=Header.at(t, "base_link"), percentage=1.0 - 0.004 * i)
        samples.append(_sample(f"{ns}battery_status", battery, t + 0.002, i + 1))
    log = McapLog(path)
    log.add_metadata(RECORDING_METADATA, {"namespace": namespace})
    log.add_attachment(WORLD_ATTACHMENT, "application/yaml", SEED_ROOM.read_bytes(), START_NS)
    for sample in samples:
        log.write_sample(sample)
        _, _, type_name = sample.encoding.partition(";")
        for view in convert_key(sample.key, type_name, sample.payload):
            log.write_view(view, sample.log_time_ns)
    log.finish()
    return samples
