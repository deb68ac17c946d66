"""zendock's ROS 2 face on the default middleware: real rclpy nodes (run from .venv-ros2)."""
