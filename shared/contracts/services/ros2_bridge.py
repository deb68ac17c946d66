"""The ros2_bridge service's contract."""

from __future__ import annotations

from shared import topics
from shared.contracts.model import Action, Contract, Flag, Topic
from shared.endpoints import RELIABLE
from shared.interfaces.docking import DOCK_ROBOT, UNDOCK_ROBOT
from shared.interfaces.navigation import (
    NAVIGATE_TO_POSE,
)
from shared.messages import (
    Twist,
)

CONTRACT = Contract(
    service="ros2_bridge",
    summary="zendock seen from ROS 2 (rmw_zenoh): nodes, topics, actions, forwarded only while wanted.",
    version="1.1",
    publishes=(
        Topic(topics.CMD_VEL, Twist, RELIABLE, about="from ROS 2's /cmd_vel (Twist or TwistStamped)"),
    ),
    uses_actions=(
        Action(topics.NAVIGATE_TO_POSE, NAVIGATE_TO_POSE),
        Action(topics.DOCK_ROBOT, DOCK_ROBOT),
        Action(topics.UNDOCK_ROBOT, UNDOCK_ROBOT),
    ),
    subscribes_on_demand=True,
    flags=(Flag("domain_id", "the ROS_DOMAIN_ID of its rmw_zenoh face", needed=True),),
    behaviour=("shows zendock to ROS 2: an rmw_zenoh node token for each zendock service",),
    needs=("simulator",),
    notes=("It subscribes to a robot's topics only while a ROS 2 subscriber wants them.",),
)
