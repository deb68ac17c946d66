"""Wheel odometry: the pose in the odom frame integrated from what the wheel encoders measure.

Integration is exact along the arc each step (ros2_control ``diff_drive_controller`` odometry,
``integrateExact``). With ``odom_noise`` > 0 each wheel's travel per step is scaled by ``1 + N(0, noise)``,
the usual model of wheel slip and radius error, so the odometry drifts from the ground truth.
"""

from __future__ import annotations

import math

import numpy as np

from services.simulator.robot_model import DiffDriveParams, Twist2D, WheelSpeeds, wheel_speeds_from_twist
from shared.geometry import Pose2D, wrap_angle


def integrate_arc(pose: Pose2D, linear_m: float, angular_rad: float) -> Pose2D:
    """Advance ``pose`` by ``linear_m`` along an arc that turns by ``angular_rad``."""
    if abs(angular_rad) < 1e-9:
        mid = pose.yaw + 0.5 * angular_rad
        return Pose2D(pose.x + linear_m * math.cos(mid), pose.y + linear_m * math.sin(mid), pose.yaw)
    radius = linear_m / angular_rad
    yaw_end = pose.yaw + angular_rad
    return Pose2D(
        pose.x + radius * (math.sin(yaw_end) - math.sin(pose.yaw)),
        pose.y - radius * (math.cos(yaw_end) - math.cos(pose.yaw)),
        wrap_angle(yaw_end),
    )


class Odometry:
    """odom -> base_link from wheel encoders; the odom frame's origin is where the robot was at reset."""

    def __init__(
        self, params: DiffDriveParams, odom_noise: float = 0.0, rng: np.random.Generator | None = None
    ):
        if not (math.isfinite(odom_noise) and odom_noise >= 0.0):
            raise ValueError(f"odom_noise must be >= 0, got {odom_noise!r}")
        self.params = params
        self.odom_noise = odom_noise
        self._rng = rng if rng is not None else np.random.default_rng(0)
        self.pose = Pose2D()
        self.twist = Twist2D()
        self.wheel_speeds = WheelSpeeds()
        #: Accumulated wheel angles (joint_states positions), radians.
        self.left_wheel_rad = 0.0
        self.right_wheel_rad = 0.0

    def reset(self) -> None:
        """Restart the odom frame at the robot's current pose."""
        self.pose = Pose2D()
        self.twist = Twist2D()
        self.wheel_speeds = WheelSpeeds()

    def update(self, measured: Twist2D, dt_s: float) -> None:
        """Integrate one step in which the base moved with ``measured`` (the wheels' rolling motion).

        The encoders count the (noisy) wheel turns; odometry reads them with the nominal radius.
        """
        wheels = wheel_speeds_from_twist(measured, self.params)
        left_rad, right_rad = wheels.left_radps * dt_s, wheels.right_radps * dt_s
        if self.odom_noise > 0.0:
            gain = 1.0 + self.odom_noise * self._rng.standard_normal(2)
            left_rad, right_rad = left_rad * float(gain[0]), right_rad * float(gain[1])
        self.left_wheel_rad += left_rad
        self.right_wheel_rad += right_rad
        r, b = self.params.wheel_radius_m, self.params.wheel_separation_m
        linear_m = 0.5 * r * (left_rad + right_rad)
        angular_rad = r * (right_rad - left_rad) / b
        self.pose = integrate_arc(self.pose, linear_m, angular_rad)
        self.wheel_speeds = WheelSpeeds(left_rad / dt_s, right_rad / dt_s)
        self.twist = Twist2D(linear_m / dt_s, angular_rad / dt_s)
