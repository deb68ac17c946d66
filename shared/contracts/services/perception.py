"""The perception service's contract."""

from __future__ import annotations

from shared import topics
from shared.contracts.model import Contract, Flag, Topic
from shared.contracts.services.common import DOCK_DATABASE, IMAGE_QOS
from shared.controllers import DETECTORS
from shared.endpoints import RELIABLE, SENSOR_DATA, QoS
from shared.messages import (
    CameraInfo,
    DockDetection,
    Image,
    PoseStamped,
    TFMessage,
)

CONTRACT = Contract(
    service="perception",
    summary="The dock from pixels: ArUco markers in camera images become detected_dock_pose.",
    publishes=(
        Topic(
            topics.DETECTED_DOCK_POSE,
            PoseStamped,
            SENSOR_DATA,
            about="the dock in base_link, from pixels alone",
        ),
        Topic(topics.DOCK_DETECTIONS, DockDetection, RELIABLE, about="each detection with its quality"),
        Topic(
            topics.ARUCO_DEBUG_IMAGE,
            Image,
            IMAGE_QOS,
            when="optional: a view for people",
            about="the image with the markers drawn, while someone listens",
        ),
    ),
    subscribes=(
        Topic(
            topics.CAMERA_INFO,
            CameraInfo,
            QoS(reliable=False, depth=1),
            about="the latest only; best effort, as the camera sends it",
        ),
        Topic(topics.TF_STATIC, TFMessage, QoS(depth=20)),
        Topic(topics.CAMERA_IMAGE, Image, IMAGE_QOS, when="while someone listens to its detections"),
    ),
    flags=(
        DOCK_DATABASE,
        Flag("dock_detector", " or ".join(DETECTORS) + " (without a camera it stays idle)"),
    ),
    behaviour=(
        "sees the dock: with the robot 1 m in front of the dock, detected_dock_pose within 5 cm of the truth",
    ),
    needs=("simulator",),
)
