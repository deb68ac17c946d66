"""Graceful motion control for the final approach: a smooth curve onto the dock's axis.

The control law is Park & Kuipers, "A smooth control law for graceful motion of differential wheeled
mobile robots in 2D environments", ICRA 2011, as Nav2 implements it in nav2_graceful_controller
(``smooth_control_law.cpp``, ``ego_polar_coords.hpp``) and uses it in opennav_docking's controller.

In egocentric polar coordinates of the target seen from the robot -- distance ``r``, the target's
orientation ``phi`` and the robot's heading ``delta``, both relative to the line of sight -- the path
curvature is::

    kappa = -1/r * (k_delta * (delta - atan(-k_phi * phi)) + (1 + k_phi / (1 + (k_phi * phi)^2)) * sin(delta))

and the speed ``v = v_max / (1 + beta * |kappa|^lambda)``, capped by ``v_max * r / slowdown_radius``,
clamped to ``[v_min, v_max]``; then ``w = kappa * v`` is clamped to ``+-w_max`` and ``v`` recomputed
from the clamped ``w`` so the robot keeps to the curve.

:class:`GracefulDockController` aims the law at a target ``dock_target_past_m`` *past* the dock pose
(inside the plate), so the target is never reached and the law never has to settle at ``r -> 0``;
contact, charging or an optional distance test ends the approach. It also caps the speed so the robot
slows to about ``contact_speed_mps`` at the plate (keeping the curvature), and by default it steers on
a filtered, latency-compensated robot pose (:mod:`services.docking.pose_estimator`): close to the
target the law's 1/r gain turns millimetres of pose noise into large steering commands.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from services.docking.approach import dock_frame_error, docking_target
from services.docking.pose_estimator import PoseEstimatorParams, RobotPoseEstimator
from shared.geometry import Pose2D, wrap_angle

#: Below this distance to the target the law is singular; the command is zero.
MIN_TARGET_DISTANCE_M = 1e-6


@dataclass(frozen=True, slots=True)
class GracefulGains:
    """Gains and speed limits of the smooth control law (names follow Nav2's ``controller.*`` parameters)."""

    k_phi: float
    k_delta: float
    beta: float
    lambda_: float
    slowdown_radius_m: float
    v_linear_min_mps: float
    v_linear_max_mps: float
    v_angular_max_radps: float

    def __post_init__(self) -> None:
        if self.k_phi <= 0 or self.k_delta <= 0:
            raise ValueError(f"k_phi and k_delta must be > 0, got {self.k_phi}, {self.k_delta}")
        if self.beta < 0 or self.lambda_ <= 0:
            raise ValueError(f"beta must be >= 0 and lambda > 0, got {self.beta}, {self.lambda_}")
        if self.slowdown_radius_m <= 0:
            raise ValueError(f"slowdown_radius_m must be > 0, got {self.slowdown_radius_m}")
        if not 0 <= self.v_linear_min_mps <= self.v_linear_max_mps or self.v_angular_max_radps <= 0:
            raise ValueError("need 0 <= v_linear_min <= v_linear_max and v_angular_max > 0")


#: Nav2 opennav_docking's defaults (``controller.*`` parameters as declared in its ``controller.cpp``;
#: its documentation table gives ``v_linear_max`` 0.24 and its example file 0.15).
NAV2_DOCKING_DEFAULTS = GracefulGains(
    k_phi=3.0,
    k_delta=2.0,
    beta=0.4,
    lambda_=2.0,
    slowdown_radius_m=0.25,
    v_linear_min_mps=0.1,
    v_linear_max_mps=0.25,
    v_angular_max_radps=0.75,
)

#: zendock's gains for a 0.40 x 0.30 m robot limited to 0.5 m/s and 1.5 rad/s; tuned with
#: ``services.docking.bench`` (kinematic model, 50 ms pose latency and pose noise).
ZENDOCK_TUNED = GracefulGains(
    k_phi=5.0,
    k_delta=5.0,
    beta=0.3,
    lambda_=2.0,
    slowdown_radius_m=0.25,
    v_linear_min_mps=0.05,
    v_linear_max_mps=0.5,
    v_angular_max_radps=1.5,
)


@dataclass(frozen=True, slots=True)
class EgoPolar:
    """The target seen from the robot: distance, target orientation and robot heading w.r.t. the line of sight."""

    r_m: float
    phi_rad: float
    delta_rad: float


@dataclass(frozen=True, slots=True)
class VelocityCommand:
    """A body-frame velocity command and the curvature it follows."""

    linear_x_mps: float
    angular_z_radps: float
    curvature_per_m: float = 0.0

    def as_tuple(self) -> tuple[float, float]:
        return (self.linear_x_mps, self.angular_z_radps)


def ego_polar(target: Pose2D, robot: Pose2D, backward: bool = False) -> EgoPolar:
    """Egocentric polar coordinates of ``target`` from ``robot`` (both in one frame)."""
    dx = target.x - robot.x
    dy = target.y - robot.y
    line_of_sight = math.atan2(-dy, dx)
    if backward:
        line_of_sight += math.pi
    return EgoPolar(
        r_m=math.hypot(dx, dy),
        phi_rad=wrap_angle(target.yaw + line_of_sight),
        delta_rad=wrap_angle(robot.yaw + line_of_sight),
    )


def curvature(polar: EgoPolar, gains: GracefulGains) -> float:
    """Path curvature (1/m) of the smooth control law; 0 at the singular point ``r = 0``."""
    if polar.r_m < MIN_TARGET_DISTANCE_M:
        return 0.0
    k_phi, k_delta = gains.k_phi, gains.k_delta
    phi, delta = polar.phi_rad, polar.delta_rad
    proportional = k_delta * (delta - math.atan(-k_phi * phi))
    feedback = (1.0 + k_phi / (1.0 + (k_phi * phi) ** 2)) * math.sin(delta)
    return -(proportional + feedback) / polar.r_m


def smooth_control_law(
    target: Pose2D, robot: Pose2D, gains: GracefulGains, backward: bool = False
) -> VelocityCommand:
    """One command of the law towards ``target``, as nav2_graceful_controller computes it."""
    polar = ego_polar(target, robot, backward)
    if polar.r_m < MIN_TARGET_DISTANCE_M:
        return VelocityCommand(0.0, 0.0, 0.0)
    kappa = curvature(polar, gains)
    if backward:
        kappa = -kappa
    v = gains.v_linear_max_mps / (1.0 + gains.beta * abs(kappa) ** gains.lambda_)
    v = min(gains.v_linear_max_mps * polar.r_m / gains.slowdown_radius_m, v)
    v = min(max(v, gains.v_linear_min_mps), gains.v_linear_max_mps)
    if backward:
        v = -v
    w = kappa * v
    w_bound = min(max(w, -gains.v_angular_max_radps), gains.v_angular_max_radps)
    if kappa != 0.0:
        v = w_bound / kappa
    return VelocityCommand(v, w_bound, kappa)


@dataclass(frozen=True, slots=True)
class GracefulDockParams:
    """How :class:`GracefulDockController` uses the law for docking."""

    gains: GracefulGains = ZENDOCK_TUNED
    #: Aim this far past the dock pose (into the plate); 0 aims at the dock pose itself, as Nav2 does.
    dock_target_past_m: float = 0.2
    #: Along-axis distance short of the dock pose at which the contacts touch.
    contact_reach_m: float = 0.05
    #: Speed allowed when the contacts touch; None disables the arrival speed cap.
    contact_speed_mps: float | None = 0.1
    #: Deceleration the arrival speed cap plans with (keep it under the robot's limit).
    approach_decel_mps2: float = 0.8
    #: Stop (zero command) once within this distance of the dock pose; None leaves stopping to the caller.
    stop_distance_m: float | None = None
    #: Smooth and latency-compensate the robot pose before the law sees it; None uses raw poses.
    pose_estimator: PoseEstimatorParams | None = PoseEstimatorParams()
    #: The period the controller is meant to be stepped at (the default ``dt_s`` of :meth:`compute`).
    control_period_s: float = 0.05


#: The docking controller configured the way Nav2's docking server uses the law: target at the dock
#: pose, Nav2's default gains, no arrival speed cap, docked within 0.05 m (SimpleChargingDock's
#: ``docking_threshold``).
NAV2_DOCKING_PARAMS = GracefulDockParams(
    gains=NAV2_DOCKING_DEFAULTS,
    dock_target_past_m=0.0,
    contact_speed_mps=None,
    stop_distance_m=0.05,
    pose_estimator=None,
)

#: zendock's configuration: tuned gains, target past the plate, arrival speed capped.
ZENDOCK_PARAMS = GracefulDockParams()


class GracefulDockController:
    """Steers the robot forwards from the staging area onto the dock; the dock pose may change every tick.

    The plate is ahead of the dock pose (the robot docks driving forwards); the law itself also supports
    reverse motion (``smooth_control_law(..., backward=True)``).
    """

    def __init__(self, dock_pose: Pose2D, params: GracefulDockParams = ZENDOCK_PARAMS) -> None:
        self.params = params
        self.dock_pose = dock_pose
        self.last_command = VelocityCommand(0.0, 0.0, 0.0)
        self.estimator = RobotPoseEstimator(params.pose_estimator) if params.pose_estimator else None

    def set_dock_pose(self, dock_pose: Pose2D) -> None:
        """Use a newer dock pose (for example the pose filter's output) from the next tick on."""
        self.dock_pose = dock_pose

    def reset(self) -> None:
        """Forget the last command and the pose estimate (call before a new approach)."""
        self.last_command = VelocityCommand(0.0, 0.0, 0.0)
        if self.estimator is not None:
            self.estimator.reset()

    @property
    def target(self) -> Pose2D:
        """The point the law steers to: the dock pose pushed past the plate."""
        return docking_target(self.dock_pose, self.params.dock_target_past_m)

    def is_docked_by_distance(self, robot_pose: Pose2D) -> bool:
        """The distance test: within ``stop_distance_m`` of the dock pose (False when disabled)."""
        limit = self.params.stop_distance_m
        return limit is not None and robot_pose.distance_to(self.dock_pose) <= limit

    def estimate_pose(
        self,
        measured_pose: Pose2D,
        dt_s: float | None = None,
        pose_age_s: float | None = None,
        base_twist: tuple[float, float] | None = None,
    ) -> Pose2D:
        """The pose the law uses: the estimator's, or ``measured_pose`` itself when the estimator is off.

        The estimate is first advanced over ``dt_s`` (default ``control_period_s``) with ``base_twist``,
        the measured body velocity ``(v, w)`` when the caller has odometry, else with the last command.
        ``pose_age_s`` is how old ``measured_pose`` is (default the estimator's ``latency_s``).
        """
        if self.estimator is None:
            return measured_pose
        if self.estimator.initialised:
            dt = self.params.control_period_s if dt_s is None else dt_s
            if base_twist is not None:
                self.estimator.propagate(base_twist[0], base_twist[1], dt, measured_velocity=True)
            else:
                self.estimator.propagate(self.last_command.linear_x_mps, self.last_command.angular_z_radps, dt)
        return self.estimator.correct(measured_pose, pose_age_s)

    def compute(
        self,
        measured_pose: Pose2D,
        dt_s: float | None = None,
        pose_age_s: float | None = None,
        base_twist: tuple[float, float] | None = None,
    ) -> VelocityCommand:
        """The command for the robot's latest measured map pose (same frame as the dock pose).

        ``dt_s``, ``pose_age_s`` and ``base_twist`` feed the pose estimator (see :meth:`estimate_pose`) and
        are ignored when it is off. The returned command is assumed to be the one sent to the base; if the
        caller sends something else (a stop), it should pass the measured ``base_twist`` next time.
        """
        p = self.params
        robot_pose = self.estimate_pose(measured_pose, dt_s, pose_age_s, base_twist)
        if self.is_docked_by_distance(robot_pose):
            self.last_command = VelocityCommand(0.0, 0.0, 0.0)
            return self.last_command
        command = smooth_control_law(self.target, robot_pose, p.gains)
        if p.contact_speed_mps is not None:
            command = self._cap_arrival_speed(command, robot_pose, p.contact_speed_mps)
        self.last_command = command
        return command

    def step(self, pose_x: float, pose_y: float, pose_yaw: float) -> tuple[float, float]:
        """One control tick: ``(linear_x m/s, angular_z rad/s)`` for the robot's map pose."""
        return self.compute(Pose2D(pose_x, pose_y, pose_yaw)).as_tuple()

    def _cap_arrival_speed(
        self, command: VelocityCommand, robot_pose: Pose2D, contact_speed_mps: float
    ) -> VelocityCommand:
        """Scale v and w together (same curvature) so the robot can slow to the contact speed in time."""
        p = self.params
        along_m = dock_frame_error(robot_pose, self.dock_pose).along_m
        to_contact_m = max(0.0, -along_m - p.contact_reach_m)
        cap = math.sqrt(contact_speed_mps**2 + 2.0 * p.approach_decel_mps2 * to_contact_m)
        speed = abs(command.linear_x_mps)
        if speed <= cap:
            return command
        scale = cap / speed
        return VelocityCommand(command.linear_x_mps * scale, command.angular_z_radps * scale, command.curvature_per_m)
