"""The ros2_dds service's contract."""

from __future__ import annotations

from msgspec.structs import replace

from shared.contracts.model import Flag
from shared.contracts.services.ros2_bridge import CONTRACT as ROS2_BRIDGE_CONTRACT

#: The same promise on DDS (real rclpy): the same routes (shared/ros2/bridge_routes.py), another middleware.
CONTRACT = replace(
    ROS2_BRIDGE_CONTRACT,
    service="ros2_dds",
    version="1.1",
    summary="zendock seen from ROS 2 on DDS (real rclpy, Fast DDS): nodes, topics, actions, forwarded only while wanted.",
    flags=(Flag("domain_id", "the ROS_DOMAIN_ID of its rclpy (DDS) face", needed=True),),
    behaviour=("shows zendock to ROS 2 on DDS: an rclpy node for each zendock service that is up",),
    notes=(
        "It subscribes to a robot's topics only while a ROS 2 subscriber matches (transient-local ones "
        "always), and runs from .venv-ros2 (make ros2).",
    ),
)
