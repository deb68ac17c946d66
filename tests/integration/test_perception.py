"""The perception service on real processes: a rendered frame becomes a dock pose; bad frames are counted."""

from __future__ import annotations

import math

import numpy as np
import zenoh

from shared.geometry import Pose2D
from shared.interfaces.simulator import TELEPORT, TeleportRequest
from shared.messages import Clock, DockDetection, Header, Image, PoseStamped, Time
from shared.node import call_service
from shared.world import load_world
from tests.support.bus import KeyRecorder
from tests.support.processes import REPO_ROOT, wait_until

SEED_ROOM = str(REPO_ROOT / "deploy/worlds/seed_room.yaml")


def _teleport(bus: zenoh.Session, ns: str, pose: Pose2D) -> None:
    KeyRecorder(bus, f"{ns}/clock", Clock).wait_for(timeout_s=30.0)  # the simulator is up and stepping
    reply = call_service(
        bus,
        f"{ns}/simulator/teleport",
        TELEPORT,
        TeleportRequest(robot="", x=pose.x, y=pose.y, yaw=pose.yaw),
        timeout_s=10.0,
    )
    assert reply.success, reply.message


def test_a_rendered_frame_becomes_the_dock_pose_within_2_cm_and_2_degrees(
    spawn, bus: zenoh.Session, namespace: str
) -> None:  # type: ignore[no-untyped-def]
    dock = load_world(SEED_ROOM).docks[0].pose2d
    robot = dock.compose(Pose2D(-1.0, 0.05, 0.1))  # 1 m out, a little off the axis, turned a little
    detections = KeyRecorder(bus, f"{namespace}/detected_dock_pose", PoseStamped)
    named = KeyRecorder(bus, f"{namespace}/dock_detections", DockDetection)
    spawn("simulator", "--world", SEED_ROOM, "-p", "rtf=1", "-p", "detection.source=aruco")
    spawn("perception", "-p", f"dock_database={SEED_ROOM}")
    _teleport(bus, namespace, robot)
    truth = dock.relative_to(robot)

    def close_to_truth(msg: PoseStamped) -> bool:
        pose = msg.pose.to_pose2d()
        return math.hypot(pose.x - truth.x, pose.y - truth.y) < 0.02 and abs(
            pose.yaw - truth.yaw
        ) < math.radians(2.0)

    detections.wait_for(timeout_s=30.0)
    found = detections.wait_for(close_to_truth, timeout_s=10.0, after=max(0, detections.count - 1))
    assert found.header.frame_id == "base_link"
    tagged = named.wait_for(timeout_s=10.0)
    assert tagged.dock_id == "home" and tagged.marker_id == 0 and 0.9 < tagged.marker_range_m < 1.2


def test_bad_frames_are_counted_and_the_service_keeps_detecting(
    spawn, bus: zenoh.Session, namespace: str
) -> None:  # type: ignore[no-untyped-def]
    dock = load_world(SEED_ROOM).docks[0].pose2d
    detections = KeyRecorder(bus, f"{namespace}/detected_dock_pose", PoseStamped)
    spawn("simulator", "--world", SEED_ROOM, "-p", "rtf=1", "-p", "detection.source=aruco")
    perception = spawn("perception", "-p", f"dock_database={SEED_ROOM}")
    _teleport(bus, namespace, dock.compose(Pose2D(-0.8, 0.0, 0.0)))
    detections.wait_for(timeout_s=30.0)
    key = f"{namespace}/camera/image_raw"
    header = Header(Time(), "camera_optical_frame")
    bad = [
        Image(
            header, 4, 4, "mono8", 0, 4, np.zeros(10, dtype=np.uint8)
        ).encode(),  # data short of height * step
        Image(header, 4, 4, "yuv422", 0, 8, np.zeros(32, dtype=np.uint8)).encode(),  # unknown encoding
        Image(header, 0, 0, "mono8", 0, 0, np.zeros(0, dtype=np.uint8)).encode(),  # empty
        Image(header, 4, 4, "rgb8", 0, 4, np.zeros(16, dtype=np.uint8)).encode(),  # step shorter than a row
        b"\x93not an image",
    ]
    for payload in bad:
        bus.put(key, payload)
    seen = len(detections.messages)
    detections.wait_for(lambda _m: len(detections.messages) > seen + 5, timeout_s=30.0)
    assert perception.alive(), "the perception service died on bad frames"

    def ignored_a_bad_image() -> bool:
        if "ignored an image" in perception.output():
            return True
        # The camera's queue keeps only the newest frame: bad images the simulator's next frame replaced
        # before they were read are sent again.
        for payload in bad[:-1]:
            bus.put(key, payload)
        return False

    wait_until(ignored_a_bad_image, 10.0, lambda: perception.output()[-2000:])
