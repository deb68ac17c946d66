"""The planner service's wiring: the map server (:mod:`services.planner.map_server`), the layered
costmap (:mod:`services.planner.costmap_updater`), the global planner and the path follower behind the
``navigate_to_pose`` action (the navigation stack's role).

In: ``map_to_base_link_pose2d`` (the robot's map pose), ``odom`` (twist, and stamped poses that place
sensor readings at their own instant, see :mod:`shared.pose_tracking`), ``scan`` (the
costmap's obstacle layer), ``ultrasonic`` (glass: echoes the lidar cannot explain, kept in
:mod:`services.planner.glass_memory` and folded into the static layer), ``tf_static`` (sensor mounts).
Out: ``cmd_vel`` (only while a goal is active, then one zero), ``plan``, ``map`` (every
``map_publish_period_s`` and on change: Zenoh keeps no latched copy), ``costmap`` (for display).
Requests: the ``navigate_to_pose`` action, ``planner/clear_entirely_costmaps``, ``map_server/load_map``
and ``map_server/map``.

Threads and cost per tick: every callback runs on the node's executor, one at a time. Sensor callbacks
only keep the newest data; a costmap timer (``costmap_update_rate_hz`` on sim time, slower when idle)
asks a worker thread (:mod:`services.planner.costmap_thread`) to fold it into the layers and re-inflate
(:class:`~services.planner.costmap_updater.CostmapUpdater`), so the 20 Hz control tick neither waits for
an update nor inflates: it reads the newest snapshot. A* runs on another worker thread against such a
read-only snapshot. Both workers' results come back through ``node.post``.

A goal's life (planning, following, replanning, recoveries, its end and error code) is
:class:`~services.planner.navigation_run.NavigationRun`: the node hands it a snapshot (pose, twist, cost
grid, clocks) each control tick and on each event, and carries out the orders it returns.
"""

from __future__ import annotations

import itertools
import math
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from services.planner.behavior_server import BehaviorServer
from services.planner.costmap_thread import CostmapThread, LockedPoseTrack
from services.planner.costmap_updater import CostmapUpdater, glass_speed_limit
from services.planner.global_planner import GlobalPlanner
from services.planner.goal_check import check_goal_on_grid, goal_pose
from services.planner.map_messages import costmap_message, nav2_costmap_message, path_message
from services.planner.map_server import MapServer
from services.planner.navigation_run import Ending, NavigationRun, NavOrders, NavSnapshot, Phase
from services.planner.occupancy_map import OccupancyMap
from services.planner.params import Params, load_initial_map
from services.planner.path_following import FollowPath
from services.planner.path_server import PathServer
from services.planner.planning_worker import PlanningWorker, PlanOutcome, PlanRequest
from services.planner.pose_sequences import PoseSequences
from services.planner.recovery import GlassClearing
from services.planner.world_hold import WorldHold
from shared import topics
from shared.action import ActionServer, ServerGoalHandle
from shared.geometry import Pose2D
from shared.interfaces.costmap import (
    GET_COSTMAP,
    GLOBAL_COSTMAP_CLEAR,
    GLOBAL_COSTMAP_GET,
    LOCAL_COSTMAP_CLEAR,
    LOCAL_COSTMAP_GET,
    REGION_CLEARS,
    ClearCostmapAroundPoseRequest,
    ClearCostmapAroundPoseResponse,
    ClearCostmapAroundRobotRequest,
    ClearCostmapAroundRobotResponse,
    ClearCostmapExceptRegionRequest,
    ClearCostmapExceptRegionResponse,
    GetCostmapRequest,
    GetCostmapResponse,
    region_clear_service,
)
from shared.interfaces.map_server import (
    COSTMAP_TOPIC,
)
from shared.interfaces.navigation import (
    CLEAR_COSTMAPS_SERVICE,
    CLEAR_ENTIRE_COSTMAP,
    NAVIGATE_TO_POSE,
    ClearEntireCostmapRequest,
    ClearEntireCostmapResponse,
    NavigateErrorCode,
    NavigateToPoseFeedback,
    NavigateToPoseGoal,
    NavigateToPoseResult,
)
from shared.messages import (
    Duration,
    Float64MultiArray,
    Header,
    LaserScan,
    OccupancyGrid,
    Odometry,
    PacingHold,
    Path,
    Pose,
    PoseStamped,
    Range,
    TFMessage,
    Twist,
)
from shared.node import RELIABLE, SENSOR_DATA, Node, QoS, ServiceError
from shared.pose_tracking import OdometrySample, PoseTrack
from shared.ratelimit import RateLimitedLogger
from shared.runtime import ServiceSpec

NavHandle = ServerGoalHandle[NavigateToPoseGoal, NavigateToPoseResult, NavigateToPoseFeedback]

#: Odometry carries the pose forward along its twist at most this far: a few odometry periods.
POSE_EXTRAPOLATION_S = 0.1
#: A robot slower than this stands still: a task starting then may trust its turning circle (glass).
STANDING_STILL_MPS = 0.02
STANDING_STILL_RADPS = 0.05


class _Durations:
    """CPU time a callback takes on its thread (unlike wall time, not inflated when a busy machine
    deschedules the process): count, mean, p99 of the last 2000, max."""

    def __init__(self) -> None:
        self.count = 0
        self.total_s = 0.0
        self.max_s = 0.0
        self.recent: deque[float] = deque(maxlen=2000)

    def add(self, seconds: float) -> None:
        self.count += 1
        self.total_s += seconds
        self.max_s = max(self.max_s, seconds)
        self.recent.append(seconds)

    def summary(self) -> str:
        if not self.count:
            return "never ran"
        p99 = sorted(self.recent)[int(0.99 * (len(self.recent) - 1))]
        return (
            f"{self.count} runs, mean {1000 * self.total_s / self.count:.2f} ms, "
            f"p99 {1000 * p99:.2f} ms, max {1000 * self.max_s:.2f} ms"
        )


def _result(code: NavigateErrorCode, message: str = "") -> NavigateToPoseResult:
    return NavigateToPoseResult(error_code=int(code), error_msg=message)


class PlannerService:
    """The navigation server on a node; see the module docstring."""

    def __init__(self, node: Node, params: Params) -> None:
        self._node = node
        self._params = params
        self._log = node.log
        self._say = RateLimitedLogger(node.log, interval_s=5.0)
        occupancy, source = load_initial_map(params)
        self._tracker = PoseTrack(max_extrapolation_s=POSE_EXTRAPOLATION_S)
        #: The worker reads the track through this view; the executor adds samples holding its lock.
        self._shared_track = LockedPoseTrack(self._tracker)
        self._control_time = _Durations()
        #: Control ticks' worth of sim seconds a goal was driven under a glass speed limit, all goals, and
        #: the metres driven in them.
        self._glass_slowed_s = 0.0
        self._glass_slowed_m = 0.0
        node.stats.extra = {
            **node.stats.extra,
            topics.GLASS_SLOWED_STAT: 0.0,
            topics.GLASS_SLOWED_M_STAT: 0.0,
        }
        self._costmap_time = _Durations()
        self._layers = CostmapUpdater(params, self._shared_track, node.log)
        self._costmap = CostmapThread(
            self._layers,
            lambda _update_s: node.post(self._on_costmap_updated),
            node.log,
            self._costmap_time.add,
        )
        self._worker = PlanningWorker(
            params.planner_params(), lambda outcome: node.post(self._on_plan_outcome, outcome)
        )
        #: The search behind a way through suspected glass (on the control thread, after a failed plan).
        self._way_planner = GlobalPlanner(params.planner_params())
        self._planning_in_flight = False
        self._generations = itertools.count(1)
        self._run: NavigationRun | None = None
        self._handle: NavHandle | None = None
        self._last_cmd = (0.0, 0.0)
        self._last_costmap_update_s = -math.inf

        self._cmd_pub = node.create_publisher(Twist, topics.CMD_VEL, RELIABLE)
        #: On sim time: the world held while the planner works with its robot standing (world_hold.py).
        self._world_hold = WorldHold(
            node.create_publisher(PacingHold, topics.PACING_HOLD, RELIABLE).publish, node.use_sim_time
        )
        #: The sim time of the last snapshot: the tick the next command answers.
        self._snapshot_s = -math.inf
        self._plan_pub = node.create_publisher(Path, topics.PLAN, RELIABLE)
        self._costmap_pub = node.create_publisher(OccupancyGrid, COSTMAP_TOPIC, QoS(reliable=False, depth=1))
        node.create_subscription(Float64MultiArray, topics.POSE2D, self._on_pose, QoS(depth=1))
        node.create_subscription(Odometry, topics.ODOM, self._on_odom, QoS(depth=5))
        node.create_subscription(LaserScan, topics.SCAN, self._layers.add_scan, SENSOR_DATA)
        if params.use_range_layer:
            node.create_subscription(Range, topics.ULTRASONIC, self._layers.add_range, SENSOR_DATA)
        node.create_subscription(TFMessage, topics.TF_STATIC, self._layers.add_mounts, QoS(depth=5))
        node.create_service(CLEAR_ENTIRE_COSTMAP, CLEAR_COSTMAPS_SERVICE, self._on_clear_costmaps)
        # Nav2's names for what Nav2 scripts ask (shared/interfaces/costmap.py): one costmap answers both.
        node.create_service(CLEAR_ENTIRE_COSTMAP, GLOBAL_COSTMAP_CLEAR, self._on_clear_costmaps)
        node.create_service(CLEAR_ENTIRE_COSTMAP, LOCAL_COSTMAP_CLEAR, self._on_clear_local_costmap)
        region_clears: dict[str, Callable[[Any], Any]] = {
            "except_region": self._on_clear_except_region,
            "around_robot": self._on_clear_around_robot,
            "around_pose": self._on_clear_around_pose,
        }
        for costmap in ("global", "local"):
            for what, srv in REGION_CLEARS:
                node.create_service(srv, region_clear_service(costmap, what), region_clears[what])
        node.create_service(GET_COSTMAP, GLOBAL_COSTMAP_GET, self._on_get_global_costmap)
        node.create_service(GET_COSTMAP, LOCAL_COSTMAP_GET, self._on_get_local_costmap)
        self._action = ActionServer(
            node,
            NAVIGATE_TO_POSE,
            topics.NAVIGATE_TO_POSE,
            on_goal=self._on_goal,
            on_accepted=self._on_accepted,
            on_cancel=self._on_cancel,
            preempt_result=lambda: _result(NavigateErrorCode.PREEMPTED, "preempted by a newer goal"),
        )
        self._paths = PathServer(
            node,
            params.planner_params(),
            robot_pose=lambda: self._tracker.current_pose(self._node.now(), self._params.pose_timeout_s),
            grid=lambda: self._costmap.grid,
            footprint_m=(params.robot_length_m, params.robot_width_m),
        )
        self._sequences = PoseSequences(node, lambda: self._params.waypoint_stop_on_failure)
        self._behaviors = BehaviorServer(
            node,
            params.behavior_params(),
            publish_cmd=self._publish_cmd,
            navigating=lambda: self._run is not None,
            follow_path=lambda poses: FollowPath(
                poses, self._params.follower_params(), self._params.follow_limits()
            ),
        )
        self._timers = [
            node.create_timer(1.0 / params.controller_rate_hz, self._on_control_tick),
            node.create_timer(1.0 / params.costmap_update_rate_hz, self._on_costmap_tick),
        ]
        self._map_server = MapServer(node, params.map_publish_period_s, self._on_map)
        if params.costmap_publish_period_s > 0:
            self._timers.append(
                node.create_timer(params.costmap_publish_period_s, self._publish_costmap, wall=True)
            )
        if occupancy is not None:
            self._map_server.set_map(occupancy, source)
        else:
            self._log.warning(
                "no map_yaml or world given: goals are refused until map_server/load_map loads one"
            )
        self._log.info(
            "navigating on %s time: control %g Hz, costmap %g Hz, replan every %g s",
            "sim" if node.use_sim_time else "wall",
            params.controller_rate_hz,
            params.costmap_update_rate_hz,
            params.replan_period_s,
        )

    def on_parameter_set(self, name: str, value: object) -> None:
        """A runtime parameter change (:mod:`shared.parameter_server`): the costmap's inflation applies at
        once; the follower's speeds are read when the next goal builds its run."""
        if name == "inflation_radius_m":
            self._costmap.change(self._layers.refresh_costmap_params)

    # --- map --------------------------------------------------------------------------------------

    def _on_map(self, occupancy: OccupancyMap) -> None:
        """A new static map (at start or from ``load_map``): the layers take it; a goal replans on it."""
        self._costmap.change(self._layers.set_map, occupancy)
        run = self._run
        if run is not None and run.phase is Phase.FOLLOWING:
            self._carry_out(run.replan(self._snapshot()))

    def _publish_costmap(self) -> None:
        grid = self._costmap.grid
        if grid is not None:
            self._costmap_pub.publish(costmap_message(grid, self._node.now(), topics.MAP_FRAME))

    def _on_clear_costmaps(self, request: ClearEntireCostmapRequest) -> ClearEntireCostmapResponse:
        """The whole costmap: the lidar's marks and all the glass the sonar heard (it is heard again as the
        robot drives; a pane seen only from its far side stays unknown until then)."""
        self._costmap.change(self._layers.clear, GlassClearing.ALL)
        return ClearEntireCostmapResponse()

    def _on_clear_local_costmap(self, request: ClearEntireCostmapRequest) -> ClearEntireCostmapResponse:
        """Round the robot, as Nav2's local costmap is: the lidar's marks, and the glass within
        ``recovery_glass_clear_radius_m`` (a recovery's clearing; the rest of the glass memory stays)."""
        pose = self._tracker.current_pose(self._node.now(), self._params.pose_timeout_s)
        # Without a pose there is no "round the robot": the lidar's marks only, the glass memory kept.
        glass = GlassClearing.AROUND_ROBOT if pose is not None else GlassClearing.KEEP
        self._costmap.change(self._layers.clear, glass, pose)
        return ClearEntireCostmapResponse()

    # Nav2's region clears: one costmap answers for both names, so a global and a local clear do the same.

    def _on_clear_except_region(
        self, request: ClearCostmapExceptRegionRequest
    ) -> ClearCostmapExceptRegionResponse:
        self._clear_square(self._robot_xy(), request.reset_distance, outside=True)
        return ClearCostmapExceptRegionResponse()

    def _on_clear_around_robot(
        self, request: ClearCostmapAroundRobotRequest
    ) -> ClearCostmapAroundRobotResponse:
        self._clear_square(self._robot_xy(), request.reset_distance, outside=False)
        return ClearCostmapAroundRobotResponse()

    def _on_clear_around_pose(self, request: ClearCostmapAroundPoseRequest) -> ClearCostmapAroundPoseResponse:
        frame = request.pose.header.frame_id.lstrip("/")
        if frame not in ("", topics.MAP_FRAME):
            raise ValueError(f"the pose must be in {topics.MAP_FRAME!r}, not {frame!r}")
        position = request.pose.pose.position
        self._clear_square((position.x, position.y), request.reset_distance, outside=False)
        return ClearCostmapAroundPoseResponse()

    def _robot_xy(self) -> tuple[float, float]:
        pose = self._tracker.current_pose(self._node.now(), self._params.pose_timeout_s)
        if pose is None:
            raise ServiceError("no robot pose (map_to_base_link_pose2d): nothing to clear round")
        return pose.x, pose.y

    def _clear_square(self, centre: tuple[float, float], side_m: float, outside: bool) -> None:
        if not (math.isfinite(side_m) and side_m > 0.0):
            raise ValueError(f"reset_distance must be a positive number of metres, got {side_m}")
        if not all(math.isfinite(c) for c in centre):
            raise ValueError(f"the pose must be finite, got {centre}")
        if self._costmap.grid is None:
            raise ServiceError("no costmap yet (no map loaded)")
        self._costmap.change(self._layers.clear_square, centre, side_m, outside)

    def _on_get_global_costmap(self, request: GetCostmapRequest) -> GetCostmapResponse:
        grid = self._costmap.grid
        if grid is None:
            raise ServiceError("no costmap yet (no map loaded)")
        return GetCostmapResponse(
            map=nav2_costmap_message(grid, self._node.now(), topics.MAP_FRAME, "global_costmap")
        )

    def _on_get_local_costmap(self, request: GetCostmapRequest) -> GetCostmapResponse:
        grid = self._costmap.grid
        now = self._node.now()
        if grid is None:
            raise ServiceError("no costmap yet (no map loaded)")
        pose = self._tracker.current_pose(now, self._params.pose_timeout_s)
        # No pose yet: no square round the robot, but the grid's frame and resolution all the same.
        window = (pose.x, pose.y, self._params.local_costmap_size_m) if pose is not None else None
        costmap = nav2_costmap_message(
            grid, now, topics.MAP_FRAME, "local_costmap", window or (0.0, 0.0, 0.0)
        )
        if pose is None:
            self._say.info(
                "local-costmap-no-pose", "local_costmap/get_costmap: no robot pose yet: an empty square"
            )
        return GetCostmapResponse(map=costmap)

    # --- sensors ----------------------------------------------------------------------------------

    def _on_pose(self, msg: Float64MultiArray) -> None:
        data = msg.data
        if len(data) < 3 or not all(math.isfinite(v) for v in data[:3]):
            self._say.warning("bad-pose", "ignored a %s message without three finite numbers", topics.POSE2D)
            return
        with self._shared_track.lock:
            self._tracker.add_pose(self._node.now(), Pose2D.from_seq(data[:3]))

    def _on_odom(self, msg: Odometry) -> None:
        twist = msg.twist.twist
        sample = OdometrySample(
            msg.header.stamp.to_sec(), msg.pose.pose.to_pose2d(), twist.linear.x, twist.angular.z
        )
        with self._shared_track.lock:
            self._tracker.add_odom(sample, self._node.now())

    def _on_costmap_tick(self) -> None:
        """Ask the costmap worker to fold in the newest scan and the sonar readings since the last update."""
        now = self._node.now()
        if self._costmap.grid is None:
            return
        rate = self._params.costmap_update_rate_hz if self._run else self._params.idle_costmap_update_rate_hz
        if self._last_costmap_update_s <= now < self._last_costmap_update_s + 1.0 / rate - 1e-6:
            return
        self._last_costmap_update_s = now
        self._costmap.request_update(now)

    def _on_costmap_updated(self) -> None:
        """The worker's update is in the snapshot: the run checks its path against it, as of now (the
        update was asked for a little earlier)."""
        run, handle = self._run, self._handle
        if run is not None and handle is not None and handle.active:
            self._carry_out(run.costmap_updated(self._snapshot()))

    # --- action -----------------------------------------------------------------------------------

    def _on_goal(self, goal: NavigateToPoseGoal) -> None:
        """Refuse what cannot be planned for; the ``ValueError``'s text is the client's reason."""
        try:
            pose = goal_pose(goal.pose)
            grid = self._costmap.grid
            if grid is None:
                raise ValueError("no map loaded: load one with map_server/load_map first")
            check_goal_on_grid(grid, pose.x, pose.y, self._params.astar_params())
        except ValueError as exc:
            self._log.info("goal refused: %s", exc)
            raise

    def _on_accepted(self, handle: NavHandle) -> None:
        if not handle.active:
            return  # preempted before it started
        now = self._node.now()
        self._behaviors.preempt("preempted by a navigate_to_pose goal")
        run = NavigationRun(goal_pose(handle.goal.pose), self._params, now, self._generations.__next__)
        self._run, self._handle = run, handle
        handle.execute()
        self._log.info("goal (%.2f, %.2f, %.2f) accepted", run.goal.x, run.goal.y, run.goal.yaw)
        self._trust_turning_circle(now)
        self._carry_out(run.start(self._snapshot(now)))

    def _on_cancel(self, handle: NavHandle) -> None:
        if self._run is not None and self._handle is handle:
            self._log.info("goal canceled")
            self._carry_out(self._run.cancel())
        elif handle.active:
            handle.canceled(_result(NavigateErrorCode.CANCELED, "canceled on request"))

    def _on_plan_outcome(self, outcome: PlanOutcome) -> None:
        self._planning_in_flight = False
        hold = self._world_hold
        now = self._node.now()
        # A hold for this plan lasts until the outcome is acted on (a first path's command is out, or the
        # next work has begun), not a moment less: the world would run on in between.
        standing = "plan" in hold.reasons
        if standing:
            hold.begin("plan outcome", now)
        hold.end("plan", now)
        try:
            run, handle = self._run, self._handle
            if run is None or handle is None or not handle.active:
                return
            first = run.plan is None
            before = run.plan
            self._carry_out(run.plan_outcome(outcome, self._snapshot()))
            if run.plan is not None and (first or (standing and run.plan is not before)):
                # The first path, or one the robot stood for: drive on it now, not a control period later.
                # The world is holding for this goal's command (the stops before it answered the tick that
                # asked for the plan, or the hold above).
                self._on_control_tick()
        finally:
            hold.end("plan outcome", self._node.now())

    def _on_control_tick(self) -> None:
        if self._behaviors.active:
            self._behaviors.tick(self._snapshot())
        run, handle = self._run, self._handle
        if run is None or handle is None:
            return
        if not handle.active:  # ended elsewhere (preempted): the new goal takes over
            self._run = self._handle = None
            return
        t0 = time.thread_time()
        snapshot = self._snapshot()
        limit = snapshot.speed_limit_mps
        if limit is not None and limit < self._params.max_linear_vel_mps:
            # sim seconds and metres driven under a glass speed limit, for reports of where the time goes
            # (the dict is replaced whole: the stats query's thread reads it whole)
            period_s = 1.0 / self._params.controller_rate_hz
            self._glass_slowed_s += period_s
            if snapshot.velocity is not None:
                self._glass_slowed_m += abs(snapshot.velocity[0]) * period_s
            self._node.stats.extra = {
                **self._node.stats.extra,
                topics.GLASS_SLOWED_STAT: self._glass_slowed_s,
                topics.GLASS_SLOWED_M_STAT: self._glass_slowed_m,
            }
        self._carry_out(run.tick(snapshot))
        self._control_time.add(time.thread_time() - t0)

    # --- the run's snapshot and orders --------------------------------------------------------------

    def _snapshot(self, now: float | None = None) -> NavSnapshot:
        now = self._node.now() if now is None else now
        self._snapshot_s = now
        timeout_s = self._params.pose_timeout_s
        tracker = self._tracker
        pose = tracker.current_pose(now, timeout_s)
        return NavSnapshot(
            now_s=now,
            wall_s=time.monotonic(),
            pose=pose,
            pose_age_s=tracker.pose_age_s(now),
            pose_carried=tracker.carried_by_odometry(now, timeout_s),
            velocity=tracker.twist(now, timeout_s),
            grid=self._costmap.grid,
            planning_in_flight=self._planning_in_flight,
            last_cmd=self._last_cmd,
            speed_limit_mps=glass_speed_limit(self._params, pose, self._costmap.heard_glass_xy),
        )

    def _carry_out(self, orders: NavOrders) -> None:
        """Do what the run says, in order: command, a way through suspicion, glass put back, plan request,
        path, clearing, feedback, the end."""
        run, handle = self._run, self._handle
        now = self._node.now()
        if orders.cmd is not None:
            self._publish_cmd(*orders.cmd, answers_s=orders.cmd_answers_s)
        hold = self._world_hold
        if orders.open_way_from is not None and run is not None:
            with hold.during("way through suspicion", now):  # two searches, on this thread
                self._costmap.change(
                    self._layers.open_way_through_suspicion, orders.open_way_from, run.goal, self._way_planner
                )
        if orders.restore_unheard_glass:
            with hold.during("glass put back", now):
                self._costmap.change(self._layers.restore_unheard_glass)
        grid = self._costmap.grid
        if orders.plan_from is not None and run is not None and grid is not None:
            if self._last_cmd == (0.0, 0.0):
                hold.begin("plan", now)  # the robot stands until the plan is back (_on_plan_outcome)
            self._planning_in_flight = True
            self._worker.submit(PlanRequest(run.generation, grid, orders.plan_from, run.goal))
        if orders.path is not None:
            self._plan_pub.publish(path_message(orders.path, now, topics.MAP_FRAME))
        if orders.clear is not None:
            with hold.during("clearing", now):
                self._costmap.change(self._layers.clear, orders.clear, orders.clear_around)
        if orders.feedback is not None and handle is not None:
            feedback = orders.feedback
            handle.publish_feedback(
                NavigateToPoseFeedback(
                    current_pose=PoseStamped(
                        Header.at(now, topics.MAP_FRAME), Pose.from_pose2d(feedback.pose)
                    ),
                    navigation_time=Duration.from_sec(feedback.navigation_time_s),
                    estimated_time_remaining=Duration.from_sec(feedback.estimated_time_remaining_s),
                    number_of_recoveries=feedback.number_of_recoveries,
                    distance_remaining=feedback.distance_remaining_m,
                )
            )
        if orders.end is not None and handle is not None:
            hold.end_all(now)
            self._run = self._handle = None
            result = _result(orders.end.code, orders.end.message)
            if orders.end.ending is Ending.SUCCEEDED:
                handle.succeed(result)
            elif orders.end.ending is Ending.CANCELED:
                handle.canceled(result)
            else:
                handle.abort(result)

    def _publish_cmd(self, linear_mps: float, angular_radps: float, answers_s: float | None = None) -> None:
        """Publish a command, saying which tick it answers: the time of the snapshot it was computed from,
        unless ``answers_s`` says an earlier one (a stop while the first plan is being made)."""
        self._last_cmd = (linear_mps, angular_radps)
        if answers_s is None:
            answers_s = self._snapshot_s
        if not self._node.use_sim_time:
            answers_s = None
        self._cmd_pub.publish(Twist.planar(linear_mps, angular_radps), answers_s=answers_s)

    def _trust_turning_circle(self, now: float) -> None:
        """A goal starts where the robot stands still: let it turn there (see
        :meth:`GlassMemory.observe_turning_circle`). Not for a goal that arrives while driving."""
        pose = self._tracker.current_pose(now, self._params.pose_timeout_s)
        velocity = self._tracker.twist(now, self._params.pose_timeout_s)
        if pose is None or velocity is None:
            return
        if abs(velocity[0]) > STANDING_STILL_MPS or abs(velocity[1]) > STANDING_STILL_RADPS:
            return
        self._costmap.change(self._layers.observe_turning_circle, pose)

    # --- shutdown ---------------------------------------------------------------------------------

    def close(self) -> None:
        self._log.info(
            "CPU per control tick: %s; per costmap update: %s",
            self._control_time.summary(),
            self._costmap_time.summary(),
        )
        if self._run is not None:
            self._carry_out(self._run.abort(NavigateErrorCode.UNKNOWN, "the planner is shutting down"))
        for timer in self._timers:
            timer.cancel()
        self._worker.close()
        self._costmap.close()
        self._action.close()
        self._behaviors.close()
        self._paths.close()
        self._sequences.close()


def _add_flags(parser: Any) -> dict[str, str]:
    parser.add_argument("--map", default=None, help="map_server YAML file (same as -p map_yaml=FILE)")
    parser.add_argument(
        "--world", default=None, help="world file rasterised into the map (same as -p world=FILE)"
    )
    return {"map": "map_yaml", "world": "world"}


SERVICE = ServiceSpec(
    "planner",
    Params,
    PlannerService,
    description="Navigation: map server, layered costmap, A* planner and regulated pure pursuit "
    "behind the navigate_to_pose action.",
    add_flags=_add_flags,
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
