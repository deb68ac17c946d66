"""``python -m services.ros2_bridge``: zendock seen, driven and navigated from ROS 2 (rmw_zenoh)."""
