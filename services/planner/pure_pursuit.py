"""Regulated Pure Pursuit: follow a planned path with (v, w) commands for a differential-drive robot.

After nav2_regulated_pure_pursuit_controller (Macenski et al., 2023, "Regulated Pure Pursuit for Robot
Path Tracking"): steer along the arc through a lookahead point (curvature ``2 y / L^2`` in the robot
frame), with the lookahead scaled by speed, and regulate the linear speed down on tight curves
(``regulated_linear_scaling_min_radius``), close to obstacles (cost regulation, inverting the inflation
formula to a distance), and on the final approach (Nav2's proportional law, or braking at a constant
rate). Large heading errors at the start are fixed by rotating in place, and the final yaw by rotating
in place once inside the xy goal tolerance (which latches, like Nav2's stateful goal checker). Before a
command goes out, the arc it commands is projected forward up to ``max_allowed_time_to_collision_s`` (and
no further than the lookahead point) over the costmap; a lethal footprint stops the robot.

State is explicit: the path, how far along it the robot has got, and whether the goal position has been
reached. Everything else is a function of the inputs to :meth:`RegulatedPurePursuit.compute_velocity_command`.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from services.planner.costmap import FREE_SPACE, LETHAL_OBSTACLE, MAX_NON_OBSTACLE, NO_INFORMATION, CostGrid
from shared.geometry import Pose2D, wrap_angle
from shared.world import ROBOT_LENGTH_M, ROBOT_WIDTH_M


class FollowStatus(enum.Enum):
    NO_PATH = "no_path"
    FOLLOWING = "following"
    ROTATING_TO_PATH = "rotating_to_path"
    ROTATING_TO_GOAL = "rotating_to_goal"
    GOAL_REACHED = "goal_reached"
    COLLISION_AHEAD = "collision_ahead"


@dataclass(frozen=True)
class PurePursuitParams:
    """Limits, lookahead and regulation settings; names follow the Nav2 controller's parameters."""

    desired_linear_vel_mps: float = 0.5
    max_angular_vel_radps: float = 1.5
    max_linear_accel_mps2: float = 1.0
    max_linear_decel_mps2: float = 1.5
    max_angular_accel_radps2: float = 3.2
    # Lookahead: |v| * lookahead_time_s clamped to [min, max] when velocity-scaled, else lookahead_dist_m.
    use_velocity_scaled_lookahead_dist: bool = True
    lookahead_dist_m: float = 0.6
    min_lookahead_dist_m: float = 0.3
    max_lookahead_dist_m: float = 0.9
    lookahead_time_s: float = 1.5
    use_interpolation: bool = True
    # Curvature regulation.
    use_regulated_linear_velocity_scaling: bool = True
    regulated_linear_scaling_min_radius_m: float = 0.9
    regulated_linear_scaling_min_speed_mps: float = 0.25
    # Cost (proximity) regulation; the inflation parameters must match the costmap's.
    use_cost_regulated_linear_velocity_scaling: bool = True
    cost_scaling_dist_m: float = 0.6
    cost_scaling_gain: float = 1.0
    inflation_cost_scaling_factor: float = 3.0
    inscribed_radius_m: float = 0.5 * min(ROBOT_LENGTH_M, ROBOT_WIDTH_M)
    # Approach: with ``approach_decel_mps2`` 0 the speed falls in proportion to the path left over its last
    # ``approach_velocity_scaling_dist_m`` (Nav2's law); above 0 it brakes at that rate to stop
    # ``APPROACH_STOP_SHORT`` of the goal tolerance short of the goal (:func:`approach_speed`).
    approach_velocity_scaling_dist_m: float = 0.6
    min_approach_linear_velocity_mps: float = 0.05
    approach_decel_mps2: float = 0.0
    # Rotate in place.
    use_rotate_to_heading: bool = True
    rotate_to_heading_angular_vel_radps: float = 1.5
    rotate_to_heading_min_angle_rad: float = 0.785
    # Goal tolerances.
    xy_goal_tolerance_m: float = 0.05
    yaw_goal_tolerance_rad: float = 0.05
    # Collision check.
    use_collision_detection: bool = True
    max_allowed_time_to_collision_s: float = 1.0
    robot_length_m: float = ROBOT_LENGTH_M
    robot_width_m: float = ROBOT_WIDTH_M
    #: How far along the path (from the last closest point) to look for the new closest point.
    max_robot_pose_search_dist_m: float = 2.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if isinstance(value, float) and not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a non-negative number, got {value}")
        for name in (
            "desired_linear_vel_mps",
            "max_angular_vel_radps",
            "min_lookahead_dist_m",
            "regulated_linear_scaling_min_radius_m",
            "cost_scaling_dist_m",
            "approach_velocity_scaling_dist_m",
            "inflation_cost_scaling_factor",
        ):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)}")
        if self.min_lookahead_dist_m > self.max_lookahead_dist_m:
            raise ValueError("min_lookahead_dist_m must not exceed max_lookahead_dist_m")

    @property
    def circumscribed_radius_m(self) -> float:
        return 0.5 * math.hypot(self.robot_length_m, self.robot_width_m)


@dataclass(frozen=True)
class VelocityCommand:
    linear_mps: float
    angular_radps: float
    status: FollowStatus
    #: Where the robot is steering to, in the map frame (``None`` when not following).
    lookahead_point: tuple[float, float] | None = None
    curvature: float = 0.0


def curvature_to(x_m: float, y_m: float) -> float:
    """Curvature of the arc from the robot (at the origin, facing +x) through ``(x, y)``."""
    d2 = x_m * x_m + y_m * y_m
    return 2.0 * y_m / d2 if d2 > 1e-3 else 0.0


def circle_segment_intersection(p1: np.ndarray, p2: np.ndarray, radius_m: float) -> np.ndarray:
    """Where the segment from ``p1`` (inside) to ``p2`` (outside) crosses the circle about the origin."""
    d = p2 - p1
    a = float(d @ d)
    if a < 1e-12:
        return p2.copy()
    b = 2.0 * float(p1 @ d)
    c = float(p1 @ p1) - radius_m * radius_m
    disc = max(0.0, b * b - 4.0 * a * c)
    t = (-b + math.sqrt(disc)) / (2.0 * a)
    return p1 + min(max(t, 0.0), 1.0) * d


def cost_regulated_speed(cost: int, desired_mps: float, params: PurePursuitParams) -> float:
    """Speed allowed at a cell of this cost: invert inflation to a distance, slow down when close."""
    if cost in (FREE_SPACE, NO_INFORMATION):
        return desired_mps
    min_distance_m = (
        params.inscribed_radius_m - math.log(cost / MAX_NON_OBSTACLE) / params.inflation_cost_scaling_factor
    )
    if min_distance_m >= params.cost_scaling_dist_m:
        return desired_mps
    return desired_mps * params.cost_scaling_gain * max(0.0, min_distance_m) / params.cost_scaling_dist_m


def project_arc(pose: Pose2D, linear_mps: float, angular_radps: float, times_s: np.ndarray) -> np.ndarray:
    """Poses ``(N, 3)`` reached after each of ``times_s`` driving the constant twist (exact arcs)."""
    t = np.asarray(times_s, dtype=float)
    yaw = pose.yaw + angular_radps * t
    if abs(angular_radps) < 1e-9:
        x = pose.x + linear_mps * t * math.cos(pose.yaw)
        y = pose.y + linear_mps * t * math.sin(pose.yaw)
    else:
        r = linear_mps / angular_radps
        x = pose.x + r * (np.sin(yaw) - math.sin(pose.yaw))
        y = pose.y - r * (np.cos(yaw) - math.cos(pose.yaw))
    return np.stack([x, y, yaw], axis=1)


#: The braking approach aims to stop this fraction of the xy goal tolerance short of the goal: the drive's
#: lag (a late pose, a command a tick late) then spends its margin inside the tolerance, not past it.
APPROACH_STOP_SHORT = 0.4


def approach_speed(remaining_m: float, cruise_mps: float, params: PurePursuitParams) -> float:
    """The fastest speed allowed with ``remaining_m`` of path left, never above ``cruise_mps``.

    Nav2's law (``approach_decel_mps2`` 0) scales the speed by the fraction of
    ``approach_velocity_scaling_dist_m`` left: the speed decays exponentially, and over the last 0.3 m the
    robot loses about half a second against full speed. Braking at a constant rate instead,
    ``v = sqrt(2 a d)``, keeps full speed until the brake must start, and the tolerance takes the last
    centimetres (0.10-0.15 s lost at 0.75 m/s^2 with the simulator's drive, a tick of lag or none).
    Never below ``min_approach_linear_velocity_mps``: the robot still reaches the tolerance.
    """
    p = params
    if p.approach_decel_mps2 > 0.0:
        short_m = APPROACH_STOP_SHORT * p.xy_goal_tolerance_m
        approach = math.sqrt(2.0 * p.approach_decel_mps2 * max(0.0, remaining_m - short_m))
    else:
        approach = cruise_mps * remaining_m / p.approach_velocity_scaling_dist_m
    return min(cruise_mps, max(approach, p.min_approach_linear_velocity_mps))


#: A robot stopped within this many xy tolerances of the goal has arrived (its pose jitters by a centimetre
#: or so as it turns on the spot); further, it overshot while braking (:meth:`RegulatedPurePursuit.confirm_goal`).
OVERSHOOT_SLACK = 1.5


class RegulatedPurePursuit:
    """Path follower. Call :meth:`set_path`, then :meth:`compute_velocity_command` every control cycle."""

    def __init__(self, params: PurePursuitParams | None = None) -> None:
        self.params = params or PurePursuitParams()
        self._path = np.zeros((0, 3))
        self._arc_length = np.zeros(0)
        self._closest_index = 0
        self._xy_goal_reached = False

    @property
    def path(self) -> np.ndarray:
        return self._path

    @property
    def closest_index(self) -> int:
        """Index of the path pose the robot was last found nearest to (never moves backwards)."""
        return self._closest_index

    @property
    def xy_goal_reached(self) -> bool:
        return self._xy_goal_reached

    def confirm_goal(self, pose: Pose2D) -> bool:
        """Judged once the robot has stopped inside the tolerances: is it still near enough the goal?

        The xy tolerance, once met, holds while the robot turns to the goal's heading (Nav2's stateful goal
        checker). A robot that met it still moving brakes first, and under load (late poses, late commands)
        braking can carry it well past the tolerance. Stopped further than :data:`OVERSHOOT_SLACK` tolerances
        from the goal, it has not arrived: the tolerance is let go, and the next command turns back.
        """
        if len(self._path) == 0:
            return False
        goal = self._path[-1]
        if (
            math.hypot(goal[0] - pose.x, goal[1] - pose.y)
            <= OVERSHOOT_SLACK * self.params.xy_goal_tolerance_m
        ):
            return True
        self._xy_goal_reached = False
        return False

    def set_path(self, poses: np.ndarray) -> None:
        """Follow a new path: ``(N, 3)`` poses in the map frame, goal last. Resets progress."""
        path = np.asarray(poses, dtype=float).reshape(-1, 3)
        if len(path) and not np.all(np.isfinite(path)):
            raise ValueError("path poses must be finite")
        self._path = path
        steps = np.hypot(*np.diff(path[:, :2], axis=0).T) if len(path) > 1 else np.zeros(0)
        self._arc_length = np.concatenate([[0.0], np.cumsum(steps)]) if len(path) else np.zeros(0)
        self._closest_index = 0
        self._xy_goal_reached = False

    def reset(self) -> None:
        """Forget the path (the follower then commands zero with ``NO_PATH``)."""
        self.set_path(np.zeros((0, 3)))

    def compute_velocity_command(
        self,
        pose: Pose2D,
        velocity: tuple[float, float],
        dt_s: float,
        costmap: CostGrid | None = None,
        speed_limit_mps: float | None = None,
    ) -> VelocityCommand:
        """One control step: robot ``pose`` (map frame), measured ``(v, w)``, cycle time ``dt_s``;
        ``speed_limit_mps`` caps the forward speed (Nav2's speed limit, here from suspected glass)."""
        p = self.params
        if len(self._path) == 0:
            return VelocityCommand(0.0, 0.0, FollowStatus.NO_PATH)
        v_now, w_now = float(velocity[0]), float(velocity[1])
        goal = self._path[-1]
        if math.hypot(goal[0] - pose.x, goal[1] - pose.y) <= p.xy_goal_tolerance_m:
            self._xy_goal_reached = True
        if self._xy_goal_reached:
            yaw_error = wrap_angle(goal[2] - pose.yaw)
            if abs(yaw_error) <= p.yaw_goal_tolerance_rad or not p.use_rotate_to_heading:
                return VelocityCommand(0.0, 0.0, FollowStatus.GOAL_REACHED)
            w = self._rotate_toward(yaw_error, w_now, dt_s)
            return self._checked(
                pose,
                0.0,
                w,
                FollowStatus.ROTATING_TO_GOAL,
                None,
                0.0,
                costmap,
                horizon_s=abs(yaw_error / w) if w else 0.0,
            )

        self._update_closest(pose)
        lookahead_m = self._lookahead_distance(v_now)
        carrot_local = self._carrot(pose, lookahead_m)
        carrot_map = pose.transform_point(float(carrot_local[0]), float(carrot_local[1]))
        carrot_dist = float(np.hypot(*carrot_local))
        angle_to_carrot = math.atan2(carrot_local[1], carrot_local[0])
        if p.use_rotate_to_heading and abs(angle_to_carrot) > p.rotate_to_heading_min_angle_rad:
            w = self._rotate_toward(angle_to_carrot, w_now, dt_s)
            return self._checked(
                pose,
                0.0,
                w,
                FollowStatus.ROTATING_TO_PATH,
                carrot_map,
                0.0,
                costmap,
                horizon_s=abs(angle_to_carrot / w) if w else 0.0,
            )

        curvature = curvature_to(float(carrot_local[0]), float(carrot_local[1]))
        v = self._regulated_speed(pose, curvature, costmap)
        if speed_limit_mps is not None:
            v = min(v, max(speed_limit_mps, 0.0))
        w = v * curvature
        if abs(w) > p.max_angular_vel_radps:
            w = math.copysign(p.max_angular_vel_radps, w)
            v = abs(w / curvature)
        # Acceleration limits against the measured twist (a velocity smoother's job, done here too).
        v = min(max(v, v_now - p.max_linear_decel_mps2 * dt_s), v_now + p.max_linear_accel_mps2 * dt_s)
        v = min(max(v, 0.0), p.desired_linear_vel_mps)
        w = v * curvature
        w = min(max(w, w_now - p.max_angular_accel_radps2 * dt_s), w_now + p.max_angular_accel_radps2 * dt_s)
        w = min(max(w, -p.max_angular_vel_radps), p.max_angular_vel_radps)
        return self._checked(
            pose, v, w, FollowStatus.FOLLOWING, carrot_map, curvature, costmap, max_distance_m=carrot_dist
        )

    def _rotate_toward(self, angle_rad: float, w_now: float, dt_s: float) -> float:
        """Nav2 ``rotateToHeading``: full rotation speed, accel-limited, slowed to stop at the heading."""
        p = self.params
        sign = 1.0 if angle_rad > 0.0 else -1.0
        w = sign * min(p.rotate_to_heading_angular_vel_radps, p.max_angular_vel_radps)
        w = min(max(w, w_now - p.max_angular_accel_radps2 * dt_s), w_now + p.max_angular_accel_radps2 * dt_s)
        max_to_stop = math.sqrt(2.0 * p.max_angular_accel_radps2 * abs(angle_rad))
        if abs(w) > max_to_stop:
            w = sign * max_to_stop
        return w

    def _update_closest(self, pose: Pose2D) -> None:
        start = self._closest_index
        reach = self._arc_length[start] + self.params.max_robot_pose_search_dist_m
        stop = int(np.searchsorted(self._arc_length, reach, side="right"))
        window = self._path[start : max(stop, start + 1), :2]
        d2 = (window[:, 0] - pose.x) ** 2 + (window[:, 1] - pose.y) ** 2
        self._closest_index = start + int(np.argmin(d2))

    def _lookahead_distance(self, v_now: float) -> float:
        p = self.params
        if not p.use_velocity_scaled_lookahead_dist:
            return p.lookahead_dist_m
        return min(max(abs(v_now) * p.lookahead_time_s, p.min_lookahead_dist_m), p.max_lookahead_dist_m)

    def _carrot(self, pose: Pose2D, lookahead_m: float) -> np.ndarray:
        """Lookahead point in the robot frame: first path point at least ``lookahead_m`` away."""
        remaining = self._path[self._closest_index :, :2]
        local = pose.inverse().transform_points(remaining)
        dist = np.hypot(local[:, 0], local[:, 1])
        beyond = np.nonzero(dist >= lookahead_m)[0]
        if len(beyond) == 0:
            return local[-1]
        i = int(beyond[0])
        if i == 0 or not self.params.use_interpolation:
            return local[i]
        return circle_segment_intersection(local[i - 1], local[i], lookahead_m)

    def _regulated_speed(self, pose: Pose2D, curvature: float, costmap: CostGrid | None) -> float:
        p = self.params
        desired = p.desired_linear_vel_mps
        v = desired
        if p.use_regulated_linear_velocity_scaling and curvature != 0.0:
            radius = abs(1.0 / curvature)
            if radius < p.regulated_linear_scaling_min_radius_m:
                v = desired * radius / p.regulated_linear_scaling_min_radius_m
        if p.use_cost_regulated_linear_velocity_scaling and costmap is not None:
            v = min(v, cost_regulated_speed(costmap.cost_at(pose.x, pose.y), desired, p))
        v = max(v, p.regulated_linear_scaling_min_speed_mps)
        remaining_m = float(self._arc_length[-1] - self._arc_length[self._closest_index])
        return min(approach_speed(remaining_m, v, p), desired)

    def _checked(
        self,
        pose: Pose2D,
        v: float,
        w: float,
        status: FollowStatus,
        carrot: tuple[float, float] | None,
        curvature: float,
        costmap: CostGrid | None,
        max_distance_m: float = math.inf,
        horizon_s: float = math.inf,
    ) -> VelocityCommand:
        if (
            self.params.use_collision_detection
            and costmap is not None
            and self.collision_ahead(pose, v, w, costmap, max_distance_m, horizon_s)
        ):
            return VelocityCommand(0.0, 0.0, FollowStatus.COLLISION_AHEAD, carrot, curvature)
        return VelocityCommand(v, w, status, carrot, curvature)

    def collision_ahead(
        self,
        pose: Pose2D,
        v: float,
        w: float,
        costmap: CostGrid,
        max_distance_m: float = math.inf,
        horizon_s: float = math.inf,
    ) -> bool:
        """Would driving ``(v, w)`` put the footprint on a lethal cell within the collision time horizon?

        The arc is sampled every cell width of travel (nav2 ``isCollisionImminent``), no further than
        ``max_distance_m`` along it (the lookahead point) nor beyond ``horizon_s`` (the end of a rotation).
        Unknown cells do not count as collisions.
        """
        p = self.params
        speed = abs(v) + abs(w) * p.circumscribed_radius_m
        if speed < 1e-6:
            return False
        step_s = costmap.frame.resolution_m / speed
        horizon = min(p.max_allowed_time_to_collision_s, horizon_s + step_s)
        times = np.arange(1, math.floor(horizon / step_s) + 1) * step_s
        if len(times) == 0:
            times = np.array([horizon])
        times = times[np.abs(v) * times <= max_distance_m + costmap.frame.resolution_m]
        if len(times) == 0:
            return False
        poses = project_arc(pose, v, w, times)
        costs = costmap.footprint_costs(poses, p.robot_length_m, p.robot_width_m)
        return bool(np.any((costs >= LETHAL_OBSTACLE) & (costs != NO_INFORMATION)))
