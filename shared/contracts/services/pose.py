"""The pose service's contract."""

from __future__ import annotations

from shared import topics
from shared.contracts.model import Contract, Topic
from shared.contracts.services.common import USE_SIM_TIME, lifecycle_requests
from shared.endpoints import RELIABLE, QoS
from shared.messages import (
    Float64MultiArray,
    PoseWithCovarianceStamped,
    TFMessage,
)

CONTRACT = Contract(
    service="pose",
    summary="The robot's 2-D pose in the map, [x, y, yaw], from the tf tree (map -> odom -> base_link).",
    version="1.1",
    publishes=(
        Topic(
            topics.POSE2D,
            Float64MultiArray,
            RELIABLE,
            rate_hz=10.0,
            about="data = [x_m, y_m, yaw_rad] in the map frame",
        ),
        Topic(
            topics.AMCL_POSE,
            PoseWithCovarianceStamped,
            RELIABLE,
            max_rate_hz=10.0,
            frame_id=topics.MAP_FRAME,
            when="for Nav2 scripts (zendock's pose service always)",
            about="the pose as Nav2's amcl_pose: on moving 0.25 m or turning 0.2 rad (as AMCL), and once a second",
        ),
    ),
    subscribes=(
        Topic(topics.TF, TFMessage, QoS(reliable=False, depth=100), rate_hz=20.0),
        Topic(
            topics.TF_STATIC,
            TFMessage,
            QoS(reliable=True, depth=20),
            rate_hz=1.0,
            when="optional: needed for a target_frame other than base_link",
        ),
    ),
    serves=lifecycle_requests("pose"),
    flags=(USE_SIM_TIME,),
    behaviour=(
        "follows the robot: map_to_base_link_pose2d within 5 cm and 0.05 rad of the simulator's truth",
    ),
    needs=("simulator",),
)
