"""The planner service's parameters: one flat, validated set, mapped onto the algorithms' own settings.

The mapping keeps what must agree in agreement: the follower's footprint and inflation settings are the
costmap's (cost regulation inverts the same formula the inflation applied), and the search and the
smoother share ``cost_weight`` and ``allow_unknown``. Defaults suit the robot: footprint 0.4 x 0.3 m,
0.5 m/s, 1.5 rad/s, 1 m/s^2 and 3 rad/s^2.
"""

from __future__ import annotations

import math
from typing import Annotated

from msgspec import Meta

from services.planner.astar import AStarParams
from services.planner.behaviors import BehaviorParams, DriveStraight, Spin
from services.planner.costmap import CostmapParams, inflation_cost
from services.planner.global_planner import GlobalPlannerParams
from services.planner.goal_heading import GoalHeadingParams
from services.planner.occupancy_map import OccupancyMap, load_map
from services.planner.path_following import FollowLimits
from services.planner.pure_pursuit import PurePursuitParams
from services.planner.rasterize import map_from_world
from services.planner.smoothing import SmoothingParams
from shared.parameters import ServiceParams, runtime_settable
from shared.structs import blaming
from shared.world import ROBOT_LENGTH_M, ROBOT_WIDTH_M, load_world

#: When a runtime change of a follower setting takes effect: each goal builds its follower.
NEXT_GOAL = "at the next navigation goal"


class Params(ServiceParams):
    """Parameters of ``python -m services.planner`` (``-p name=value`` or a YAML file)."""

    # map
    map_yaml: Annotated[str, Meta(description="map_server YAML loaded at start (wins over world)")] = ""
    world: Annotated[
        str, Meta(description="world file rasterised into the map when no map_yaml is given")
    ] = ""
    map_resolution_m: Annotated[float, Meta(gt=0.0, description="cell size when rasterising the world")] = (
        0.05
    )
    map_publish_period_s: Annotated[
        float, Meta(gt=0.0, description="republish the map this often (wall clock)")
    ] = 5.0
    costmap_publish_period_s: Annotated[
        float, Meta(ge=0.0, description="publish the costmap this often (0: never)")
    ] = 1.0
    local_costmap_size_m: Annotated[
        float,
        Meta(gt=0.0, description="side of the square local_costmap/get_costmap answers, round the robot"),
    ] = 3.0
    # robot and goal
    robot_length_m: Annotated[float, Meta(gt=0.0, description="footprint length along x")] = ROBOT_LENGTH_M
    robot_width_m: Annotated[float, Meta(gt=0.0, description="footprint width along y")] = ROBOT_WIDTH_M
    max_linear_vel_mps: Annotated[
        float, Meta(gt=0.0, description="top speed", extra=runtime_settable(NEXT_GOAL))
    ] = 0.5
    max_angular_vel_radps: Annotated[
        float, Meta(gt=0.0, description="top turn rate", extra=runtime_settable(NEXT_GOAL))
    ] = 1.5
    max_linear_accel_mps2: Annotated[float, Meta(gt=0.0)] = 1.0
    max_linear_decel_mps2: Annotated[float, Meta(gt=0.0)] = 1.5
    max_angular_accel_radps2: Annotated[float, Meta(gt=0.0)] = 3.0
    regulated_linear_scaling_min_radius_m: Annotated[
        float, Meta(gt=0.0, description="curves tighter than this radius are taken proportionally slower")
    ] = 0.6
    cost_scaling_dist_m: Annotated[
        float,
        Meta(
            gt=0.0,
            description="closer than this to an obstacle the speed falls in proportion to the distance",
        ),
    ] = 0.4
    approach_velocity_scaling_dist_m: Annotated[
        float,
        Meta(
            gt=0.0,
            description="over this last stretch of the path the speed falls in proportion to what is left",
        ),
    ] = 0.3
    approach_decel_mps2: Annotated[
        float,
        Meta(
            ge=0.0,
            description="above 0: the path's end is met braking at this rate, full speed until the brake must "
            "start, instead of approach_velocity_scaling_dist_m's proportional slowing (0: that law)",
        ),
    ] = 0.75
    open_loop_acceleration: Annotated[
        bool,
        Meta(description="ramp from the last command (true) or from the measured twist, which lags (false)"),
    ] = True
    xy_goal_tolerance_m: Annotated[float, Meta(gt=0.0)] = 0.05
    yaw_goal_tolerance_rad: Annotated[float, Meta(gt=0.0)] = 0.05
    trans_stopped_velocity_mps: Annotated[
        float, Meta(gt=0.0, description="the goal counts as reached only when moving slower than this ...")
    ] = 0.05
    rot_stopped_velocity_radps: Annotated[
        float, Meta(gt=0.0, description="... and turning slower than this")
    ] = 0.1
    # costmap
    inflation_radius_m: Annotated[
        float,
        Meta(
            ge=0.0,
            description="obstacles cost this far out",
            extra=runtime_settable("at once: the costmap is inflated again and the next plan uses it"),
        ),
    ] = 0.55
    cost_scaling_factor: Annotated[float, Meta(gt=0.0)] = 3.0
    obstacle_max_range_m: Annotated[
        float, Meta(ge=0.0, description="lidar hits further than this do not mark")
    ] = 2.5
    raytrace_max_range_m: Annotated[float, Meta(ge=0.0, description="lidar beams clear up to this far")] = 3.0
    costmap_update_rate_hz: Annotated[
        float, Meta(gt=0.0, description="sensor data folded in this often (sim time)")
    ] = 5.0
    scan_beam_stride: Annotated[
        int, Meta(ge=1, description="use every n-th lidar beam (2 halves the lidar's cost)")
    ] = 1
    idle_costmap_update_rate_hz: Annotated[
        float, Meta(gt=0.0, description="the same without an active goal")
    ] = 1.0
    use_range_layer: Annotated[
        bool,
        Meta(
            description="fold the ultrasonic range into the costmap (off: glass is invisible, for experiments)"
        ),
    ] = True
    glass_memory_file: Annotated[
        str,
        Meta(description="keep the sonar's glass in this file across restarts (empty: forget it on exit)"),
    ] = ""
    glass_suspicion_radius_m: Annotated[
        float,
        Meta(
            ge=0.0,
            description="unlooked-at floor this close to glass the sonar heard counts as glass (0: off)",
        ),
    ] = 0.3
    glass_echo_hold_s: Annotated[
        float,
        Meta(
            ge=0.0,
            description="each unexplained sonar echo's whole arc counts as glass this long (sim "
            "seconds), whatever the evidence model makes of it: a pane's end heard at the cone's edge (0: off)",
        ),
    ] = 2.0
    glass_pane_extension_m: Annotated[
        float,
        Meta(
            ge=0.0,
            description="a marked pane counts as going on along its own line this far past its ends, through "
            "floor the sonar has never looked at and never closer to a wall than a robot's width: its unseen "
            "end (0: off)",
        ),
    ] = 1.5
    glass_trusted_range_m: Annotated[
        float,
        Meta(
            gt=0.0,
            description="a sonar echo from this far gives the glass memory half the evidence of a near "
            "one, from 0.5 m farther an eighth (Nav2's phi): a far echo's arc is wide and mostly open floor; far "
            "glass is still held for glass_echo_hold_s",
        ),
    ] = 2.0
    glass_slowdown_radius_m: Annotated[
        float,
        Meta(
            ge=0.0,
            description="closer than this to glass the sonar has heard ahead, the speed falls in "
            "proportion to the distance (0: off)",
        ),
    ] = 0.8
    glass_slowdown_min_speed_mps: Annotated[float, Meta(gt=0.0, description="... but never below this")] = (
        0.15
    )
    lidar_mount: Annotated[
        tuple[float, float, float], Meta(description="base_link -> lidar_link until tf_static says otherwise")
    ] = (0.10, 0.0, 0.0)
    ultrasonic_mount: Annotated[
        tuple[float, float, float],
        Meta(description="base_link -> ultrasonic_link until tf_static says otherwise"),
    ] = (0.20, 0.0, 0.0)
    # planning
    cost_weight: Annotated[
        float, Meta(ge=0.0, description="how strongly inflation cost lengthens a step")
    ] = 3.0
    allow_unknown: bool = False
    arrive_along_goal_heading: Annotated[
        bool,
        Meta(
            description="a path that would arrive more than 1.6 rad off the goal's heading ends along it where "
            "there is room, instead of turning on the spot at the goal"
        ),
    ] = True
    prefer_room_to_turn: Annotated[
        bool,
        Meta(
            description="avoid gaps only the inscribed circle fits through when a path with room to turn exists"
        ),
    ] = True
    snap_radius_m: Annotated[
        float, Meta(ge=0.0, description="a blocked start or goal snaps this far at most")
    ] = 0.3
    waypoint_stop_on_failure: Annotated[
        bool,
        Meta(
            description="follow_waypoints ends at a waypoint it cannot reach (else records it as missed and goes on)",
            extra=runtime_settable("at the next waypoint that fails"),
        ),
    ] = False
    replan_period_s: Annotated[
        float, Meta(gt=0.0, description="replan this often while following (sim time)")
    ] = 1.0
    min_replan_interval_s: Annotated[
        float, Meta(ge=0.0, description="urgent replans no more often than this")
    ] = 0.2
    # control and action
    controller_rate_hz: Annotated[float, Meta(gt=0.0)] = 20.0
    feedback_rate_hz: Annotated[float, Meta(gt=0.0)] = 5.0
    pose_timeout_s: Annotated[float, Meta(gt=0.0, description="an older pose holds the robot still ...")] = (
        0.5
    )
    carried_pose_timeout_s: Annotated[
        float,
        Meta(
            gt=0.0,
            description="... unless fresh odometry carries it forward: then only a map pose older than this",
        ),
    ] = 2.0
    no_pose_timeout_s: Annotated[
        float, Meta(gt=0.0, description="abort with NO_POSE after this long without one (sim and wall time)")
    ] = 5.0
    navigation_timeout_s: Annotated[
        float, Meta(ge=0.0, description="abort with TIMEOUT after this long (0: never)")
    ] = 0.0
    # recovery
    progress_timeout_s: Annotated[float, Meta(gt=0.0, description="stuck if no progress for this long")] = (
        10.0
    )
    required_movement_m: Annotated[float, Meta(gt=0.0, description="progress: move this far ...")] = 0.25
    required_rotation_rad: Annotated[float, Meta(gt=0.0, description="... or turn this much")] = 0.5
    blocked_timeout_s: Annotated[
        float, Meta(gt=0.0, description="a collision ahead this long starts a recovery")
    ] = 2.0
    #: A robot stopped for a collision ahead, turning or creeping a little and stopped again is never blocked
    #: for blocked_timeout_s at a time, and its moves count as progress (beside a glass pane, measurement 106).
    #: So the time blocked is summed as well: blocked_timeout_s of it in all, within blocked_window_s and
    #: blocked_radius_m, is blocked too.
    blocked_window_s: Annotated[
        float,
        Meta(gt=0.0, description="blocked_timeout_s in all within this long (sim) starts a recovery too ..."),
    ] = 20.0
    blocked_radius_m: Annotated[
        float,
        Meta(gt=0.0, description="... counting the time blocked within this distance of where the robot is"),
    ] = 0.5
    max_recoveries: Annotated[int, Meta(ge=0)] = 6
    backup_distance_m: Annotated[float, Meta(gt=0.0)] = 0.15
    backup_speed_mps: Annotated[float, Meta(gt=0.0)] = 0.1
    recovery_wait_s: Annotated[float, Meta(ge=0.0, description="after clearing, let the sensors refill")] = (
        0.5
    )
    recovery_glass_clear_radius_m: Annotated[
        float,
        Meta(gt=0.0, description="recoveries that clear glass memory forget it only this close to the robot"),
    ] = 1.0

    def __post_init__(self) -> None:
        # a ConfigError names the file and the problem, before connecting
        if self.map_yaml:
            with blaming("map_yaml"):
                load_map(self.map_yaml)
        if self.world:
            with blaming("world"):
                load_world(self.world)
        for name in ("lidar_mount", "ultrasonic_mount"):
            mount = getattr(self, name)
            if not all(math.isfinite(v) for v in mount):
                raise ValueError(f"{name}: a mount is three finite numbers [x, y, yaw], got {list(mount)}")
        self.costmap_params()
        self.follower_params()
        self.planner_params()
        self.recovery_backup()

    def costmap_params(self) -> CostmapParams:
        return CostmapParams(
            robot_length_m=self.robot_length_m,
            robot_width_m=self.robot_width_m,
            inflation_radius_m=self.inflation_radius_m,
            cost_scaling_factor=self.cost_scaling_factor,
            obstacle_max_range_m=self.obstacle_max_range_m,
            raytrace_max_range_m=self.raytrace_max_range_m,
        )

    def planner_params(self) -> GlobalPlannerParams:
        """Search and smoothing share ``cost_weight`` and ``allow_unknown`` (see GlobalPlannerParams)."""
        costmap = self.costmap_params()
        room_to_turn = int(
            inflation_cost(
                costmap.circumscribed_radius_m, costmap.inscribed_radius_m, costmap.cost_scaling_factor
            )
        )
        return GlobalPlannerParams(
            astar=self.astar_params(),
            smoothing=SmoothingParams(cost_weight=self.cost_weight, allow_unknown=self.allow_unknown),
            preferred_clearance_cost=room_to_turn if self.prefer_room_to_turn else 0,
            goal_heading=self._goal_heading_params() if self.arrive_along_goal_heading else None,
        )

    def _goal_heading_params(self) -> GoalHeadingParams:
        """The curved end judges its time by the path follower's own speed model."""
        follower = self.follower_params()
        return GoalHeadingParams(
            max_linear_mps=follower.desired_linear_vel_mps,
            max_angular_radps=follower.max_angular_vel_radps,
            slow_radius_m=follower.regulated_linear_scaling_min_radius_m,
            min_curve_speed_mps=follower.regulated_linear_scaling_min_speed_mps,
            max_corner_rad=follower.rotate_to_heading_min_angle_rad,
        )

    def astar_params(self) -> AStarParams:
        return AStarParams(
            cost_weight=self.cost_weight, snap_radius_m=self.snap_radius_m, allow_unknown=self.allow_unknown
        )

    def follower_params(self) -> PurePursuitParams:
        """The follower's footprint and inflation settings are the costmap's, so cost regulation
        inverts the same formula the inflation applied."""
        costmap = self.costmap_params()
        return PurePursuitParams(
            desired_linear_vel_mps=self.max_linear_vel_mps,
            max_angular_vel_radps=self.max_angular_vel_radps,
            max_linear_accel_mps2=self.max_linear_accel_mps2,
            max_linear_decel_mps2=self.max_linear_decel_mps2,
            max_angular_accel_radps2=self.max_angular_accel_radps2,
            rotate_to_heading_angular_vel_radps=self.max_angular_vel_radps,
            regulated_linear_scaling_min_radius_m=self.regulated_linear_scaling_min_radius_m,
            approach_velocity_scaling_dist_m=self.approach_velocity_scaling_dist_m,
            approach_decel_mps2=self.approach_decel_mps2,
            cost_scaling_dist_m=self.cost_scaling_dist_m,
            inflation_cost_scaling_factor=costmap.cost_scaling_factor,
            inscribed_radius_m=costmap.inscribed_radius_m,
            xy_goal_tolerance_m=self.xy_goal_tolerance_m,
            yaw_goal_tolerance_rad=self.yaw_goal_tolerance_rad,
            robot_length_m=self.robot_length_m,
            robot_width_m=self.robot_width_m,
        )

    def behavior_params(self) -> BehaviorParams:
        """The spin, back-up, drive-on-heading and wait behaviours': the footprint and top speeds."""
        return BehaviorParams(
            robot_length_m=self.robot_length_m,
            robot_width_m=self.robot_width_m,
            max_linear_vel_mps=self.max_linear_vel_mps,
            max_angular_vel_radps=self.max_angular_vel_radps,
            angular_accel_radps2=self.max_angular_accel_radps2,
        )

    def follow_limits(self) -> FollowLimits:
        """When a path given to follow_path counts as reached, stuck or blocked: navigation's own limits."""
        return FollowLimits(
            controller_period_s=1.0 / self.controller_rate_hz,
            required_movement_m=self.required_movement_m,
            required_rotation_rad=self.required_rotation_rad,
            progress_timeout_s=self.progress_timeout_s,
            blocked_timeout_s=self.blocked_timeout_s,
            trans_stopped_mps=self.trans_stopped_velocity_mps,
            rot_stopped_radps=self.rot_stopped_velocity_radps,
            open_loop_acceleration=self.open_loop_acceleration,
        )

    def recovery_look_around(self) -> Spin:
        """A recovery's look round after it forgot heard glass: one turn in place, given four times the
        time it needs at full speed (a turn that would put a corner on an obstacle stops short)."""
        turn = 2.0 * math.pi
        return Spin(turn, 4.0 * turn / self.max_angular_vel_radps, self.behavior_params())

    def recovery_backup(self) -> DriveStraight:
        """A recovery's back-up: ``backup_distance_m`` in reverse, given four times the time it needs."""
        return DriveStraight(
            self.backup_distance_m,
            -self.backup_speed_mps,
            4.0 * self.backup_distance_m / self.backup_speed_mps,
            self.behavior_params(),
        )


def load_initial_map(params: Params) -> tuple[OccupancyMap | None, str]:
    """The map named by the parameters and where it came from; ``(None, "")`` when none is given."""
    if params.map_yaml:
        return load_map(params.map_yaml), params.map_yaml
    if params.world:
        return map_from_world(load_world(params.world), resolution_m=params.map_resolution_m), params.world
    return None, ""
