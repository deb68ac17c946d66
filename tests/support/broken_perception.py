"""A deliberately broken perception for the conformance kit's own test: ``zendock conform perception`` must
fail it, naming each of the four mistakes it makes at once.

It "sees" the dock from the simulator's ground truth and the dock database (no pixels), one detection per
camera frame, and then:

- stamps its detections ``camera_optical_frame`` while the numbers are in base_link;
- turns the dock's yaw by pi (the dock pose facing away from the robot);
- publishes 51 copies of each detection per camera frame;
- subscribes without announcing its subscriptions (no endpoint tokens for them).

Written on ``examples/wire.py``, as a replacement's author would write one.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))

from wire import BadMessage, Node, header, parse_options, planar_pose, pose_msg, seconds_of, unpack

COPIES_PER_FRAME = 51

options = parse_options("perception", __doc__ or "")
node = Node(options)
dock_x, dock_y, dock_yaw = yaml.safe_load(Path(options.params["dock_database"]).read_text())["docks"][0][
    "pose"
]
detected = node.publisher("detected_dock_pose", "geometry_msgs/msg/PoseStamped", reliable=False)
detections = node.publisher("dock_detections", "zendock_msgs/msg/DockDetection")
robot: dict[str, tuple[float, float, float]] = {}


def on_truth(sample: Any) -> None:
    try:
        robot["pose"] = planar_pose(unpack(sample.payload.to_bytes())["pose"])
    except (BadMessage, KeyError, TypeError):
        pass  # the kit's malformed payloads: refused, as a service must


def on_camera_info(sample: Any) -> None:
    try:
        stamp = seconds_of(unpack(sample.payload.to_bytes())["header"]["stamp"])
    except (BadMessage, KeyError, TypeError):
        return
    if "pose" not in robot:
        return
    x, y, yaw = robot["pose"]
    dx, dy = dock_x - x, dock_y - y
    along, aside = math.cos(yaw) * dx + math.sin(yaw) * dy, -math.sin(yaw) * dx + math.cos(yaw) * dy
    turned = math.atan2(math.sin(dock_yaw - yaw + math.pi), math.cos(dock_yaw - yaw + math.pi))
    pose = pose_msg(along, aside, turned)
    msg = {"header": header(stamp, "camera_optical_frame"), "pose": pose}
    for _ in range(COPIES_PER_FRAME):
        detected.publish(msg)
    detections.publish(
        {
            "header": msg["header"],
            "dock_id": "home",
            "marker_id": 0,
            "pose": pose,
            "reprojection_error_px": 0.0,
            "marker_range_m": math.hypot(along, aside),
        }
    )


subscribers = [
    node.session.declare_subscriber(node.key("ground_truth_pose"), on_truth),
    node.session.declare_subscriber(node.key("camera/camera_info"), on_camera_info),
]
node.declare_ready()
sys.exit(node.run(0.1, lambda: None))
