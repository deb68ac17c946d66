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
    Float64MultiArray,
    Image,
    PoseStamped,
    TFMessage,
)

CONTRACT = Contract(
    service="perception",
    summary="The dock from pixels: ArUco markers in camera images become detected_dock_pose.",
    version="1.2",
    publishes=(
        Topic(
            topics.DETECTED_DOCK_POSE,
            PoseStamped,
            SENSOR_DATA,
            max_rate_hz=15.0,
            frame_id=topics.BASE_FRAME,
            about="the dock in base_link, from pixels alone: at most one per camera frame",
        ),
        Topic(
            topics.DOCK_DETECTIONS,
            DockDetection,
            RELIABLE,
            max_rate_hz=15.0,
            frame_id=topics.BASE_FRAME,
            about="each detection with its quality: at most one per dock in view per camera frame",
        ),
        Topic(
            topics.ARUCO_DEBUG_IMAGE,
            Image,
            IMAGE_QOS,
            max_rate_hz=15.0,
            frame_id=topics.CAMERA_OPTICAL_FRAME,
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
        Topic(
            topics.POSE2D,
            Float64MultiArray,
            QoS(depth=1),
            when="optional: settles a marker's mirror ambiguity",
            about="the robot's [x, y, yaw] in the map: the dock database's heading, seen from the robot",
        ),
    ),
    flags=(
        DOCK_DATABASE,
        Flag("dock_detector", " or ".join(DETECTORS) + " (without a camera it stays idle)"),
    ),
    behaviour=(
        "sees the dock: with the robot 1 m in front of the dock, detected_dock_pose within 5 cm and 0.1 rad "
        "of the truth",
        "sees the dock from 0.4 to 3 m and 40 degrees aside: at each of 13 viewpoints the world has room for "
        "the median detection over 1.5 s within 2 cm plus 2 cm a metre of range and 0.1 rad of the truth, "
        "none turned more than 0.3 rad",
    ),
    needs=("simulator", "pose"),
    notes=(
        "The dock pose is where base_link stands when the robot is docked, facing the dock: the robot's "
        "heading there is the pose's yaw. The marker is on the dock's face 0.20 m ahead of that pose along "
        "its heading (the robot's front, half its 0.40 m length), facing back towards the robot, upright, "
        "its centre 0.10 m above the floor (half its size plus 0.02 m for a marker larger than 0.16 m); the "
        "camera is 0.10 m above the floor too.",
        "`detected_dock_pose` and each `dock_detections` message carry that pose in base_link, stamped with the "
        "camera image's stamp. With several docks in view, `detected_dock_pose` is the nearest; "
        "`dock_detections` has one message per dock seen in the frame.",
        "`DockDetection.pose`: the dock pose as above; `reprojection_error_px`: the RMS distance, in pixels, "
        "between the marker's detected corners and its corners projected back from the pose given; "
        "`marker_range_m`: the camera-to-marker distance.",
        "The camera (`camera/image_raw`): `mono8`, 640x480, 70 degrees horizontal field of view, a pinhole "
        "without distortion; `camera/camera_info` gives its K and P. Images are in `camera_optical_frame` "
        "(z forward, x right, y down), placed on base_link by `tf_static` (base_link -> camera_link -> "
        "camera_optical_frame).",
        "A marker seen from the side admits two poses, mirror images about the line of sight (IPPE gives "
        "both); both stand upright, and at 2-3 m a few pixels' noise can make the wrong one fit better in "
        "every frame (60 degrees off at 30 degrees aside). zendock's perception takes, among fits up to 4 "
        "times the best residual, the one nearer the dock database's heading seen from the robot's pose "
        "(`map_to_base_link_pose2d`); `zendock conform` looks from 0.4 to 3 m and 40 degrees aside.",
        "Markers are ArUco, of the world's `aruco_dictionary` (DICT_4X4_50 by default), `marker_size_m` "
        "wide (black border included).",
    ),
)
