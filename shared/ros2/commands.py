"""What ROS 2 sends zendock on its command topics, handled alike by both faces (rmw_zenoh and DDS).

``/cmd_vel`` drives the robot; ``/goal_pose`` (RViz's goal tool) becomes a ``navigate_to_pose`` goal;
``/initialpose`` (RViz's pose estimate) sets what the simulated localiser believes. A pose in a frame
zendock does not plan or localise in is refused, counted and logged by the face's ``refuse``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from shared import topics
from shared.interfaces.simulator import SET_LOCALISATION, SetLocalisationRequest, SetLocalisationResponse
from shared.messages import PoseStamped, PoseWithCovarianceStamped, Twist
from shared.node import RELIABLE, Node, ServiceError
from shared.ros2.bridge_routes import GOAL_POSE, INITIAL_POSE

#: ``refuse(kind, format, *args)``: count the refusal under ``kind`` and log it at most once per interval.
Refuse = Callable[..., None]


class RosCommands:
    """The robot's command topics from ROS 2 onto zendock's keys; ``navigate`` sends a navigation goal."""

    def __init__(self, node: Node, refuse: Refuse, navigate: Callable[[PoseStamped], None]) -> None:
        self._node = node
        self._refuse = refuse
        self._navigate = navigate
        self._cmd_vel = node.create_publisher(Twist, topics.CMD_VEL, RELIABLE)

    def handle(self, ros_topic: str, msg: Any) -> None:
        """One converted message from ROS 2 on ``ros_topic`` (relative to the face's ROS namespace)."""
        if isinstance(msg, Twist):
            self._cmd_vel.publish(msg)
        elif ros_topic == GOAL_POSE and isinstance(msg, PoseStamped):
            self.goal_pose(msg)
        elif ros_topic == INITIAL_POSE and isinstance(msg, PoseWithCovarianceStamped):
            self.initial_pose(msg)

    def goal_pose(self, goal: PoseStamped) -> None:
        frame = goal.header.frame_id.lstrip("/")
        if frame not in ("", topics.MAP_FRAME):
            self._refuse(
                "goal-frame",
                "refused a goal in frame %r: zendock plans in %r",
                goal.header.frame_id,
                topics.MAP_FRAME,
            )
            return
        target = goal.pose.to_pose2d()
        self._node.log.info(
            "goal from ROS 2: navigating to (%.2f, %.2f, %.2f)", target.x, target.y, target.yaw
        )
        self._navigate(goal)

    def initial_pose(self, estimate: PoseWithCovarianceStamped) -> None:
        frame = estimate.header.frame_id.lstrip("/")
        if frame not in ("", topics.MAP_FRAME):
            self._refuse(
                "initialpose-frame",
                "refused an initial pose in frame %r: zendock localises in %r",
                estimate.header.frame_id,
                topics.MAP_FRAME,
            )
            return
        belief = estimate.pose.pose.to_pose2d()

        def done(reply: SetLocalisationResponse | None, error: ServiceError | None) -> None:
            if error is not None or reply is None or not reply.success:
                self._refuse(
                    "initialpose-failed",
                    "the simulator's localiser did not take the initial pose: %s",
                    error or (reply.message if reply else "no reply"),
                )
            else:
                self._node.log.info(
                    "initial pose from ROS 2: the localiser now believes (%.2f, %.2f, %.2f)",
                    belief.x,
                    belief.y,
                    belief.yaw,
                )

        self._node.call_async(
            SET_LOCALISATION,
            topics.SIM_SET_LOCALISATION,
            SetLocalisationRequest(x=belief.x, y=belief.y, yaw=belief.yaw),
            done,
        )
