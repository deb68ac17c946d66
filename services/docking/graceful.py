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

zendock's configuration adds what a loaded, late control loop needs (see :class:`GracefulDockParams`):
the target recedes to stay ``target_lookahead_m`` ahead near the plate, beta eases off far from it, a
robot facing well away turns on the spot first (as Nav2's graceful controller's initial rotation), the
last stretch only holds the dock's heading, and commands still on their way to the base can be
predicted through (``command_delay_s``).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

from services.docking.approach import dock_frame_error, docking_target
from services.docking.pose_estimator import PoseEstimatorParams, RobotPoseEstimator
from shared.geometry import Pose2D, wrap_angle

#: Below this distance to the target the law is singular; the command is zero.
MIN_TARGET_DISTANCE_M = 1e-6


def speed_to_brake_in_time(
    distance_m: float, end_speed_mps: float, decel_mps2: float, hold_s: float
) -> float:
    """The top speed that, held ``hold_s`` and then braked at ``decel_mps2``, is down to ``end_speed_mps``
    within ``distance_m``: ``v**2 <= end**2 + 2 * a * (d - v * hold)`` solved for ``v`` (never below ``end``)."""
    a_hold = decel_mps2 * hold_s
    return max(
        end_speed_mps,
        -a_hold + math.sqrt(a_hold**2 + end_speed_mps**2 + 2.0 * decel_mps2 * max(0.0, distance_m)),
    )


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
    #: Keep the target at least this far ahead of the robot along the dock's axis (None: fixed target).
    #: Close to the plate the law's gain grows as 1/r, so a command held a moment too long (a late
    #: control tick) swings the heading; a target that recedes keeps the gain bounded there, and the
    #: robot converges onto the axis as a line follower does.
    target_lookahead_m: float | None = 0.5
    #: Far from the plate the speed falls less on curves: beta ramps from the gains' own at
    #: ``near_distance_m`` to ``far_beta`` at ``far_distance_m`` (distances to the dock pose along its
    #: axis). Turning early costs no precision, and with beta 0.3 the law never turns faster than
    #: about 0.5 rad/s, so an approach that starts askew would crawl round its first curve. From 0.6 m
    #: out beta is 0: the speed is then bounded only by the top turn rate (``v <= w_max / |kappa|``), so a
    #: robot handed over side-on does not crawl into the axis (docs/measurements, measurement 77). None: off.
    far_beta: float | None = 0.0
    near_distance_m: float = 0.35
    far_distance_m: float = 0.6
    #: Where the law asks for a sharper curve than this (it would crawl round it), turn on the spot
    #: towards the heading it wants, as Nav2's graceful controller rotates first, until the curvature has
    #: fallen below half of it; only further than ``pivot_min_distance_m`` from the dock pose (along its
    #: axis). None: never.
    pivot_curvature_per_m: float | None = 5.0
    pivot_min_distance_m: float = 0.35
    #: Angular deceleration the turn on the spot plans with (it slows to stop where the curve eases).
    pivot_decel_radps2: float = 3.0
    #: The last stretch, this far from the dock pose (along its axis), only holds the dock's heading
    #: (``w = -align_gain * yaw error``, at most ``align_max_radps``): any law that still corrects a lateral
    #: offset there turns it into yaw at the contacts (about ``k_phi * lateral / r``), and the contacts
    #: care more about yaw than about a millimetre sideways. None: the law steers to the end.
    align_distance_m: float | None = 0.15
    align_gain_per_s: float = 4.0
    align_max_radps: float = 0.3
    #: Along-axis distance short of the dock pose at which the contacts touch.
    contact_reach_m: float = 0.05
    #: Dead time from a command to the base's response (transport, the base's own loop): the law steers
    #: from the pose the robot will have when this command takes effect, predicted with the commands still
    #: on their way (a Smith predictor). 0: steer from the estimated pose as it is.
    command_delay_s: float = 0.0
    #: Speed allowed when the contacts touch; None disables the arrival speed cap.
    contact_speed_mps: float | None = 0.08
    #: The cap slows to the contact speed this far before the contacts' reach: the robot's and the dock's
    #: poses are a few millimetres off along the axis, and a plate nearer than believed would be met above
    #: the contact speed (docs/measurements, measurement 78). A tick later than the cap counts on
    #: (``arrival_hold_periods``) eats into the margin and into the base's 1 m/s**2 of braking above the cap's.
    arrival_margin_m: float = 0.005
    #: Deceleration the arrival speed cap plans with (keep it under the robot's braking limit, 2.5 m/s**2
    #: on the simulated base). Braking harder starts the slowdown later, so less of the approach is driven
    #: slowly (measurement 78).
    approach_decel_mps2: float = 1.5
    #: How many control periods the cap counts a command to hold for before the next one takes over: two,
    #: because at high speed-ups a tick can come up to a period late in simulated time (the world waits only
    #: for a command more than ``lockstep_factor`` periods late; measurement 88).
    arrival_hold_periods: float = 2.0
    #: How long the base drives on a command that turns out to be the last before its ``cmd_vel`` watchdog
    #: stops it (the simulated base's ``drive.cmd_vel_timeout_s``): the docking service killed mid-approach,
    #: the link stalled. The cap also keeps each command one the robot could end on: held this long, then
    #: braked at ``last_command_decel_mps2``, it still meets the plate at no more than the contact speed
    #: (docs/measurements, measurement 105). None: count on the next command coming.
    last_command_hold_s: float | None = 0.3
    #: The braking the watchdog's stop is counted on for: under the simulated base's 2.5 m/s**2.
    last_command_decel_mps2: float = 2.0
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
    target_lookahead_m=None,
    far_beta=None,
    pivot_curvature_per_m=None,
    align_distance_m=None,
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
        #: Commands sent within the last ``command_delay_s``: (time issued on the controller's clock, v, w).
        self._in_flight: deque[tuple[float, float, float]] = deque()
        self._clock_s = 0.0
        self._pivoting = False

    def set_dock_pose(self, dock_pose: Pose2D) -> None:
        """Use a newer dock pose (for example the pose filter's output) from the next tick on."""
        self.dock_pose = dock_pose

    def reset(self) -> None:
        """Forget the last command and the pose estimate (call before a new approach)."""
        self.last_command = VelocityCommand(0.0, 0.0, 0.0)
        self.forget_commands()
        self._pivoting = False
        if self.estimator is not None:
            self.estimator.reset()

    def forget_commands(self) -> None:
        """The commands computed lately were not sent (the robot was held still): predict without them."""
        self._in_flight.clear()

    def predict_pose(self, robot_pose: Pose2D) -> Pose2D:
        """Where ``robot_pose`` will be once the commands still on their way have been carried out."""
        pose = robot_pose
        items = list(self._in_flight)
        for i, (issued_s, v, w) in enumerate(items):
            until_s = items[i + 1][0] if i + 1 < len(items) else self._clock_s
            if until_s > issued_s:
                pose = pose.advance(v, w, until_s - issued_s)
        return pose

    @property
    def target(self) -> Pose2D:
        """The point the law steers to from afar: the dock pose pushed past the plate."""
        return docking_target(self.dock_pose, self.params.dock_target_past_m)

    def target_for(self, robot_pose: Pose2D) -> Pose2D:
        """The point the law steers to from ``robot_pose``: :attr:`target`, or further on along the dock's
        axis so that it stays ``target_lookahead_m`` ahead of the robot."""
        past_m = self.params.dock_target_past_m
        if self.params.target_lookahead_m is not None:
            along_m = dock_frame_error(robot_pose, self.dock_pose).along_m
            past_m = max(past_m, along_m + self.params.target_lookahead_m)
        return docking_target(self.dock_pose, past_m)

    def gains_at(self, robot_pose: Pose2D) -> GracefulGains:
        """The law's gains from ``robot_pose``: beta eased far from the plate (see ``far_beta``)."""
        p = self.params
        if p.far_beta is None:
            return p.gains
        distance_m = -dock_frame_error(robot_pose, self.dock_pose).along_m
        span_m = max(p.far_distance_m - p.near_distance_m, 1e-9)
        fraction = min(1.0, max(0.0, (distance_m - p.near_distance_m) / span_m))
        return replace(p.gains, beta=p.gains.beta + fraction * (p.far_beta - p.gains.beta))

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
                self.estimator.propagate(
                    self.last_command.linear_x_mps, self.last_command.angular_z_radps, dt
                )
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
        self._clock_s += p.control_period_s if dt_s is None else dt_s
        while self._in_flight and self._in_flight[0][0] < self._clock_s - p.command_delay_s - 1e-9:
            self._in_flight.popleft()
        robot_pose = self.predict_pose(robot_pose)
        if self.is_docked_by_distance(robot_pose):
            self.last_command = VelocityCommand(0.0, 0.0, 0.0)
            return self.last_command
        target, gains = self.target_for(robot_pose), self.gains_at(robot_pose)
        command = smooth_control_law(target, robot_pose, gains)
        if self._should_pivot(command, robot_pose):
            command = self._pivot(command, ego_polar(target, robot_pose), gains)
        else:
            if p.contact_speed_mps is not None:
                command = self._cap_arrival_speed(command, robot_pose, p.contact_speed_mps)
            command = self._hold_heading_at_the_end(command, robot_pose)
        self.last_command = command
        if p.command_delay_s > 0.0:
            self._in_flight.append((self._clock_s, command.linear_x_mps, command.angular_z_radps))
        return command

    def _hold_heading_at_the_end(self, command: VelocityCommand, robot_pose: Pose2D) -> VelocityCommand:
        """Within ``align_distance_m`` of the dock pose: steer only to the dock's heading."""
        p = self.params
        error = dock_frame_error(robot_pose, self.dock_pose)
        if p.align_distance_m is None or -error.along_m > p.align_distance_m or command.linear_x_mps <= 0.0:
            return command
        w = min(max(-p.align_gain_per_s * error.yaw_rad, -p.align_max_radps), p.align_max_radps)
        return VelocityCommand(command.linear_x_mps, w, w / command.linear_x_mps)

    def _should_pivot(self, command: VelocityCommand, robot_pose: Pose2D) -> bool:
        p = self.params
        if p.pivot_curvature_per_m is None:
            return False
        threshold = 0.5 * p.pivot_curvature_per_m if self._pivoting else p.pivot_curvature_per_m
        far = -dock_frame_error(robot_pose, self.dock_pose).along_m > p.pivot_min_distance_m
        self._pivoting = far and abs(command.curvature_per_m) > threshold
        return self._pivoting

    def _pivot(self, command: VelocityCommand, polar: EgoPolar, gains: GracefulGains) -> VelocityCommand:
        """Turn on the spot the way the law curves, slowing to stop about where its curvature would vanish.

        The law's curvature times ``r`` changes by ``k_delta + (1 + k_phi / (1 + (k_phi phi)^2)) cos(delta)``
        per radian of heading, which turns the curvature into the angle still to turn.
        """
        slope = gains.k_delta + (1.0 + gains.k_phi / (1.0 + (gains.k_phi * polar.phi_rad) ** 2)) * math.cos(
            polar.delta_rad
        )
        to_turn_rad = abs(command.curvature_per_m) * polar.r_m / max(slope, 1.0)
        w = min(gains.v_angular_max_radps, math.sqrt(2.0 * self.params.pivot_decel_radps2 * to_turn_rad))
        return VelocityCommand(0.0, math.copysign(w, command.curvature_per_m), command.curvature_per_m)

    def step(self, pose_x: float, pose_y: float, pose_yaw: float) -> tuple[float, float]:
        """One control tick: ``(linear_x m/s, angular_z rad/s)`` for the robot's map pose."""
        return self.compute(Pose2D(pose_x, pose_y, pose_yaw)).as_tuple()

    def _cap_arrival_speed(
        self, command: VelocityCommand, robot_pose: Pose2D, contact_speed_mps: float
    ) -> VelocityCommand:
        """Scale v and w together (same curvature) so the robot can slow to the contact speed in time."""
        p = self.params
        along_m = dock_frame_error(robot_pose, self.dock_pose).along_m
        to_contact_m = max(0.0, -along_m - p.contact_reach_m - p.arrival_margin_m)
        # a command holds until the next one (a tick may come late): the robot must still brake in time
        cap = speed_to_brake_in_time(
            to_contact_m,
            contact_speed_mps,
            p.approach_decel_mps2,
            p.control_period_s * p.arrival_hold_periods,
        )
        if p.last_command_hold_s is not None:
            # ... and if no next one comes, the base's watchdog stops it later, and harder
            cap = min(
                cap,
                speed_to_brake_in_time(
                    to_contact_m, contact_speed_mps, p.last_command_decel_mps2, p.last_command_hold_s
                ),
            )
        speed = abs(command.linear_x_mps)
        if speed <= cap:
            return command
        scale = cap / speed
        return VelocityCommand(
            command.linear_x_mps * scale, command.angular_z_radps * scale, command.curvature_per_m
        )
