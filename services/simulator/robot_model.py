"""The two-wheeled robot's drive: command twist -> wheel speeds -> the twist the motors can deliver.

The limits mirror what a real base enforces twice: the drive controller clamps and rate-limits the
commanded twist (ros2_control ``diff_drive_controller`` SpeedLimiter), then each wheel motor saturates at
its top speed (Gazebo ``diff_drive`` plugin). A saturated wheel scales both wheels by the same factor, so
the robot keeps the commanded curvature and simply drives it slower.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated

from msgspec import Meta

from shared.models.component import ComponentParams
from shared.world import ROBOT_LENGTH_M, ROBOT_WIDTH_M


class DiffDriveParams(ComponentParams, frozen=True):
    """Geometry and limits of the differential drive (values of a small indoor base)."""

    wheel_separation_m: Annotated[float, Meta(gt=0)] = 0.26
    wheel_radius_m: Annotated[float, Meta(gt=0)] = 0.033
    max_linear_mps: Annotated[float, Meta(gt=0)] = 0.5
    max_angular_radps: Annotated[float, Meta(gt=0)] = 1.5
    max_linear_accel: Annotated[float, Meta(gt=0, description="m/s^2")] = 1.0
    max_angular_accel: Annotated[float, Meta(gt=0, description="rad/s^2")] = 3.0
    #: Braking is harder than speeding up (diff_drive_controller's max_deceleration): the watchdog's stop
    #: from full speed takes 0.2 s.
    max_linear_decel: Annotated[float, Meta(gt=0, description="m/s^2")] = 2.5
    max_angular_decel: Annotated[float, Meta(gt=0, description="rad/s^2")] = 6.0
    footprint_length_m: Annotated[float, Meta(gt=0)] = ROBOT_LENGTH_M
    footprint_width_m: Annotated[float, Meta(gt=0)] = ROBOT_WIDTH_M
    mass_kg: Annotated[float, Meta(gt=0)] = 5.0

    @property
    def max_wheel_speed_radps(self) -> float:
        """A wheel's top speed: the one that drives the robot straight at ``max_linear_mps``."""
        return self.max_linear_mps / self.wheel_radius_m


@dataclass(frozen=True, slots=True)
class Twist2D:
    """Body velocity in base_link: forward speed and yaw rate (no lateral component: non-holonomic)."""

    linear_mps: float = 0.0
    angular_radps: float = 0.0


@dataclass(frozen=True, slots=True)
class WheelSpeeds:
    """Wheel angular speeds, positive when the wheel drives the robot forward."""

    left_radps: float = 0.0
    right_radps: float = 0.0


def wheel_speeds_from_twist(twist: Twist2D, params: DiffDriveParams) -> WheelSpeeds:
    """Inverse kinematics of a differential drive."""
    half = 0.5 * params.wheel_separation_m
    return WheelSpeeds(
        (twist.linear_mps - twist.angular_radps * half) / params.wheel_radius_m,
        (twist.linear_mps + twist.angular_radps * half) / params.wheel_radius_m,
    )


def twist_from_wheel_speeds(wheels: WheelSpeeds, params: DiffDriveParams) -> Twist2D:
    """Forward kinematics of a differential drive."""
    r = params.wheel_radius_m
    return Twist2D(
        0.5 * r * (wheels.right_radps + wheels.left_radps),
        r * (wheels.right_radps - wheels.left_radps) / params.wheel_separation_m,
    )


def _clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


def _rate_limit(target: float, previous: float, max_accel: float, max_decel: float, dt_s: float) -> float:
    slowing = abs(target) < abs(previous) and target * previous >= 0.0
    step = (max_decel if slowing else max_accel) * dt_s
    return previous + _clamp(target - previous, step)


def limit_twist(command: Twist2D, previous: Twist2D, dt_s: float, params: DiffDriveParams) -> Twist2D:
    """The twist the base delivers this step for ``command``, given last step's delivered twist.

    Order as on a real base: velocity clamp, acceleration limit (diff_drive_controller SpeedLimiter), then
    per-wheel saturation with a common scale factor. A non-finite command counts as a stop.
    """
    v_cmd = command.linear_mps if math.isfinite(command.linear_mps) else 0.0
    w_cmd = command.angular_radps if math.isfinite(command.angular_radps) else 0.0
    v = _clamp(v_cmd, params.max_linear_mps)
    w = _clamp(w_cmd, params.max_angular_radps)
    v = _rate_limit(v, previous.linear_mps, params.max_linear_accel, params.max_linear_decel, dt_s)
    w = _rate_limit(w, previous.angular_radps, params.max_angular_accel, params.max_angular_decel, dt_s)
    wheels = wheel_speeds_from_twist(Twist2D(v, w), params)
    fastest = max(abs(wheels.left_radps), abs(wheels.right_radps))
    if fastest > params.max_wheel_speed_radps:
        scale = params.max_wheel_speed_radps / fastest
        v, w = v * scale, w * scale
    return Twist2D(v, w)


class DiffDrive:
    """The drive's state between steps: the twist it delivered last, which the acceleration limit needs."""

    def __init__(self, params: DiffDriveParams | None = None) -> None:
        self.params = params or DiffDriveParams()
        self.delivered = Twist2D()

    def step(self, command: Twist2D, dt_s: float) -> Twist2D:
        self.delivered = limit_twist(command, self.delivered, dt_s, self.params)
        return self.delivered

    def stop(self) -> None:
        """Forget the delivered twist (after a teleport the wheels stand still)."""
        self.delivered = Twist2D()
