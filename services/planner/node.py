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
folds it into the layers and re-inflates (:class:`~services.planner.costmap_updater.CostmapUpdater`), so the 20 Hz control tick finds a cached snapshot. A* runs on
a worker thread against that read-only snapshot and its result comes back through ``node.post``.

A goal's life: PLANNING (held still until the first path) -> FOLLOWING (regulated pure pursuit; replan
every ``replan_period_s``, and at once when the costmap blocks the path or the follower sees a collision
ahead) -> SUCCEEDED inside the goal tolerances. A collision ahead that lasts ``blocked_timeout_s``, no
progress for ``progress_timeout_s``, or a failed plan starts a recovery: BACKING_UP (only over free
cells), then CLEARING (the lidar layer is cleared; every second recovery also forgets glass round the
robot, or all glass once planning has failed past the fourth; the layers refill for
``recovery_wait_s``), then PLANNING again. After ``max_recoveries`` the goal is ABORTED with the error
code of the last failure. These timeouts run on the control loop's own clock (sim time, each tick
counting at most four periods), so a machine too busy to run the loop on time does not make the robot
look stuck. A stale pose holds the robot still (a map pose carried forward by fresh odometry is stale
only after ``carried_pose_timeout_s``); NO_POSE after ``no_pose_timeout_s``.
"""

from __future__ import annotations

import enum
import math
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

from services.planner.costmap_updater import CostmapUpdater
from services.planner.goal_check import check_goal_on_grid, goal_pose
from services.planner.map_messages import costmap_message, path_message
from services.planner.map_server import MapServer
from services.planner.occupancy_map import OccupancyMap
from services.planner.params import Params, load_initial_map
from services.planner.plan_monitor import ActivePlan, ProgressChecker
from services.planner.planning_worker import PlanningWorker, PlanOutcome, PlanRequest
from services.planner.pure_pursuit import FollowStatus, RegulatedPurePursuit
from services.planner.recovery import BackUp, BackUpStatus, GlassClearing, glass_clearing
from shared import topics
from shared.action import ActionServer, ServerGoalHandle
from shared.frames import clock_went_back
from shared.geometry import Pose2D
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
    Path,
    Pose,
    PoseStamped,
    Range,
    TFMessage,
    Twist,
)
from shared.node import RELIABLE, SENSOR_DATA, Node, QoS
from shared.pose_tracking import OdometrySample, PoseTrack
from shared.ratelimit import RateLimitedLogger
from shared.runtime import run_service

NavHandle = ServerGoalHandle[NavigateToPoseGoal, NavigateToPoseResult, NavigateToPoseFeedback]

#: The path ahead this close to the robot is the follower's business, not a reason to replan.
BLOCKED_CHECK_SKIP_M = 0.15
#: Odometry carries the pose forward along its twist at most this far: a few odometry periods.
POSE_EXTRAPOLATION_S = 0.1
#: No periodic replanning this close to the goal (a new path would reset the follower's goal latch).
NO_REPLAN_WITHIN_M = 0.3
#: Feedback's time estimate uses the measured speed above this, else the speed limit.
ETA_MIN_SPEED_MPS = 0.05
#: A robot slower than this stands still: a task starting then may trust its turning circle (glass).
STANDING_STILL_MPS = 0.02
STANDING_STILL_RADPS = 0.05


class Phase(enum.Enum):
    PLANNING = "planning"
    FOLLOWING = "following"
    BACKING_UP = "backing_up"
    CLEARING = "clearing"


#: Failures to find a path, as against failures to follow one.
PLANNING_FAILURES = frozenset(
    {NavigateErrorCode.NO_VALID_PATH, NavigateErrorCode.START_OCCUPIED, NavigateErrorCode.GOAL_OCCUPIED}
)


@dataclass
class _Task:
    """One navigation goal being worked on."""

    handle: NavHandle
    goal: Pose2D
    #: Identifies the plan requests that belong to the current attempt; outcomes of others are stale.
    generation: int
    started_s: float
    progress: ProgressChecker
    phase: Phase = Phase.PLANNING
    plan: ActivePlan | None = None
    recoveries: int = 0
    #: The current recovery began because no path was found (not because following failed).
    recovering_from_planning: bool = False
    last_plan_request_s: float = -math.inf
    replan_wanted: bool = False
    blocked_since_s: float | None = None
    pose_lost_since_s: float | None = None
    pose_lost_since_wall_s: float = 0.0
    wait_until_s: float = 0.0
    last_feedback_s: float = -math.inf
    last_tick_s: float | None = None
    #: Control time: sim time as the control loop lived it, each tick counting at most four periods.
    #: The stuck, blocked and recovery timeouts run on it, so a machine too busy to run the loop on
    #: time stretches them instead of blaming the robot.
    clock_s: float = 0.0


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
        return (f"{self.count} runs, mean {1000 * self.total_s / self.count:.2f} ms, "
                f"p99 {1000 * p99:.2f} ms, max {1000 * self.max_s:.2f} ms")


def _restart_timers(task: _Task, now: float) -> None:
    """After the clock jumped back: every deadline of the task counts from ``now``."""
    task.started_s = now
    task.last_plan_request_s = -math.inf
    task.blocked_since_s = None
    task.pose_lost_since_s = None
    task.last_feedback_s = -math.inf
    task.last_tick_s = None
    task.progress.reset()


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
        self._layers = CostmapUpdater(params, self._tracker, node.log)
        self._follower = RegulatedPurePursuit(params.follower_params())
        self._backup = BackUp(params.backup_params())
        self._worker = PlanningWorker(params.planner_params(), lambda outcome: node.post(self._on_plan_outcome, outcome))
        self._planning_in_flight = False
        self._generation = 0
        self._task: _Task | None = None
        self._last_cmd = (0.0, 0.0)
        self._last_costmap_update_s = -math.inf
        self._control_time = _Durations()
        self._costmap_time = _Durations()

        self._cmd_pub = node.create_publisher(Twist, topics.CMD_VEL, RELIABLE)
        self._plan_pub = node.create_publisher(Path, topics.PLAN, RELIABLE)
        self._costmap_pub = node.create_publisher(OccupancyGrid, COSTMAP_TOPIC, QoS(reliable=False, depth=1))
        node.create_subscription(Float64MultiArray, topics.POSE2D, self._on_pose, QoS(depth=1))
        node.create_subscription(Odometry, topics.ODOM, self._on_odom, QoS(depth=5))
        node.create_subscription(LaserScan, topics.SCAN, self._layers.add_scan, SENSOR_DATA)
        if params.use_range_layer:
            node.create_subscription(Range, topics.ULTRASONIC, self._layers.add_range, SENSOR_DATA)
        node.create_subscription(TFMessage, topics.TF_STATIC, self._layers.add_mounts, QoS(depth=5))
        node.create_service(CLEAR_ENTIRE_COSTMAP, CLEAR_COSTMAPS_SERVICE, self._on_clear_costmaps)
        self._action = ActionServer(
            node, NAVIGATE_TO_POSE, topics.NAVIGATE_TO_POSE,
            on_goal=self._on_goal, on_accepted=self._on_accepted, on_cancel=self._on_cancel,
            preempt_result=lambda: _result(NavigateErrorCode.PREEMPTED, "preempted by a newer goal"),
        )
        self._timers = [
            node.create_timer(1.0 / params.controller_rate_hz, self._on_control_tick),
            node.create_timer(1.0 / params.costmap_update_rate_hz, self._on_costmap_tick),
        ]
        self._map_server = MapServer(node, params.map_publish_period_s, self._on_map)
        if params.costmap_publish_period_s > 0:
            self._timers.append(node.create_timer(params.costmap_publish_period_s, self._publish_costmap, wall=True))
        if occupancy is not None:
            self._map_server.set_map(occupancy, source)
        else:
            self._log.warning("no map_yaml or world given: goals are refused until map_server/load_map loads one")
        self._log.info(
            "navigating on %s time: control %g Hz, costmap %g Hz, replan every %g s",
            "sim" if node.use_sim_time else "wall", params.controller_rate_hz, params.costmap_update_rate_hz,
            params.replan_period_s,
        )

    # --- map --------------------------------------------------------------------------------------

    def _on_map(self, occupancy: OccupancyMap) -> None:
        """A new static map (at start or from ``load_map``): the layers take it; a goal replans on it."""
        self._layers.set_map(occupancy)
        task = self._task
        if task is not None and task.phase is Phase.FOLLOWING:
            self._request_plan(task, self._node.now(), urgent=True)

    def _publish_costmap(self) -> None:
        if self._layers.costmap is not None:
            self._costmap_pub.publish(costmap_message(self._layers.costmap.grid(), self._node.now(), topics.MAP_FRAME))

    def _on_clear_costmaps(self, request: ClearEntireCostmapRequest) -> ClearEntireCostmapResponse:
        self._layers.clear(GlassClearing.ALL)
        return ClearEntireCostmapResponse()

    # --- sensors ----------------------------------------------------------------------------------

    def _on_pose(self, msg: Float64MultiArray) -> None:
        data = msg.data
        if len(data) < 3 or not all(math.isfinite(v) for v in data[:3]):
            self._say.warning("bad-pose", "ignored a %s message without three finite numbers", topics.POSE2D)
            return
        self._tracker.add_pose(self._node.now(), Pose2D.from_seq(data[:3]))

    def _on_odom(self, msg: Odometry) -> None:
        twist = msg.twist.twist
        sample = OdometrySample(msg.header.stamp.to_sec(), msg.pose.pose.to_pose2d(), twist.linear.x, twist.angular.z)
        self._tracker.add_odom(sample, self._node.now())

    def _on_costmap_tick(self) -> None:
        """Fold the newest scan and the sonar readings since the last update into the costmap."""
        costmap = self._layers.costmap
        now = self._node.now()
        if costmap is None:
            return
        rate = self._params.costmap_update_rate_hz if self._task else self._params.idle_costmap_update_rate_hz
        if self._last_costmap_update_s <= now < self._last_costmap_update_s + 1.0 / rate - 1e-6:
            return
        self._last_costmap_update_s = now
        t0 = time.thread_time()
        self._layers.update(now)
        self._replan_if_blocked(costmap.grid(), now)
        self._costmap_time.add(time.thread_time() - t0)

    def _replan_if_blocked(self, grid: Any, now: float) -> None:
        """Replan at once when the updated costmap blocks the path ahead."""
        task = self._task
        if (
            task is not None
            and task.phase is Phase.FOLLOWING
            and task.plan is not None
            and not self._follower.xy_goal_reached
            and task.plan.newly_blocked(grid, self._follower.closest_index, BLOCKED_CHECK_SKIP_M)
        ):
            self._log.info("an obstacle blocks the path: replanning")
            self._request_plan(task, now, urgent=True)

    # --- action -----------------------------------------------------------------------------------

    def _on_goal(self, goal: NavigateToPoseGoal) -> None:
        """Refuse what cannot be planned for; the ``ValueError``'s text is the client's reason."""
        try:
            pose = goal_pose(goal.pose)
            if self._layers.costmap is None:
                raise ValueError("no map loaded: load one with map_server/load_map first")
            check_goal_on_grid(self._layers.grid(), pose.x, pose.y, self._params.astar_params())
        except ValueError as exc:
            self._log.info("goal refused: %s", exc)
            raise

    def _on_accepted(self, handle: NavHandle) -> None:
        if not handle.active:
            return  # preempted before it started
        now = self._node.now()
        self._generation += 1
        p = self._params
        task = _Task(
            handle, goal_pose(handle.goal.pose), self._generation, now,
            ProgressChecker(p.required_movement_m, p.required_rotation_rad, p.progress_timeout_s),
        )
        self._task = task
        self._follower.reset()
        handle.execute()
        self._log.info("goal (%.2f, %.2f, %.2f) accepted", task.goal.x, task.goal.y, task.goal.yaw)
        self._trust_turning_circle(now)
        self._request_plan(task, now)

    def _on_cancel(self, handle: NavHandle) -> None:
        task = self._task
        if task is not None and task.handle is handle:
            self._log.info("goal canceled")
            self._finish(task, "canceled", NavigateErrorCode.CANCELED, "canceled on request")
        elif handle.active:
            handle.canceled(_result(NavigateErrorCode.CANCELED, "canceled on request"))

    def _finish(self, task: _Task, how: str, code: NavigateErrorCode, message: str) -> None:
        """End the task: one zero command, then silence on cmd_vel."""
        self._publish_cmd(0.0, 0.0)
        self._task = None
        self._follower.reset()
        result = _result(code, message)
        if how == "succeeded":
            task.handle.succeed(result)
        elif how == "canceled":
            task.handle.canceled(result)
        else:
            self._log.warning("goal aborted (%s): %s", code.name, message)
            task.handle.abort(result)

    # --- planning ---------------------------------------------------------------------------------

    def _request_plan(self, task: _Task, now: float, urgent: bool = False) -> None:
        """Plan from the current pose on the worker, or remember to once the one in flight is back."""
        if self._planning_in_flight or (urgent and now - task.last_plan_request_s < self._params.min_replan_interval_s):
            task.replan_wanted = True
            return
        pose = self._tracker.current_pose(now, self._params.pose_timeout_s)
        if pose is None or self._layers.costmap is None:
            task.replan_wanted = True
            return
        task.replan_wanted = False
        task.last_plan_request_s = now
        self._planning_in_flight = True
        self._worker.submit(PlanRequest(task.generation, self._layers.grid(), pose, task.goal))

    def _on_plan_outcome(self, outcome: PlanOutcome) -> None:
        self._planning_in_flight = False
        task = self._task
        if task is None or not task.handle.active or outcome.request.generation != task.generation:
            return
        if task.phase not in (Phase.PLANNING, Phase.FOLLOWING):
            return
        now = self._node.now()
        if outcome.path is None:
            code = {
                "goal": NavigateErrorCode.GOAL_OCCUPIED, "start": NavigateErrorCode.START_OCCUPIED,
            }.get(outcome.blocked_end, NavigateErrorCode.NO_VALID_PATH)
            pose = self._tracker.current_pose(now, self._params.pose_timeout_s)
            self._log.warning("planning failed: %s", outcome.error)
            if pose is None:
                task.replan_wanted = True
                return
            self._start_recovery(task, pose, code, outcome.error)
            return
        path = outcome.path
        task.plan = ActivePlan.from_poses(path.poses, outcome.request.grid, now)
        self._follower.set_path(path.poses)
        self._plan_pub.publish(path_message(path.poses, now, topics.MAP_FRAME))
        self._log.debug("plan: %.2f m in %.1f ms", path.length_m, 1000.0 * path.planning_time_s)
        if task.phase is Phase.PLANNING:
            task.phase = Phase.FOLLOWING
            task.blocked_since_s = None
            task.progress.reset()
            self._log.info("following a %.2f m path (planned in %.0f ms)", path.length_m, 1000.0 * path.planning_time_s)

    # --- control ----------------------------------------------------------------------------------

    def _publish_cmd(self, linear_mps: float, angular_radps: float) -> None:
        self._last_cmd = (linear_mps, angular_radps)
        self._cmd_pub.publish(Twist.planar(linear_mps, angular_radps))

    def _on_control_tick(self) -> None:
        if self._task is None:
            return
        t0 = time.thread_time()
        self._control_step()
        self._control_time.add(time.thread_time() - t0)

    def _control_step(self) -> None:
        task = self._task
        if task is None:
            return
        if not task.handle.active:  # ended elsewhere (preempted): the new goal takes over
            self._task = None
            return
        p = self._params
        now = self._node.now()
        if clock_went_back(now, task.last_tick_s):
            self._log.warning("clock jumped back to %.2f s (a simulator reset?): restarting the goal's timers", now)
            _restart_timers(task, now)
        period = 1.0 / p.controller_rate_hz
        dt = period if task.last_tick_s is None else min(max(now - task.last_tick_s, period), 4.0 * period)
        task.last_tick_s = now
        task.clock_s += dt
        if p.navigation_timeout_s > 0 and now - task.started_s > p.navigation_timeout_s:
            self._finish(task, "aborted", NavigateErrorCode.TIMEOUT,
                         f"goal not reached within navigation_timeout_s={p.navigation_timeout_s:g} s")
            return
        pose = self._fresh_pose(task, now)
        if pose is None or self._layers.costmap is None:
            return
        grid = self._layers.grid()
        if task.phase is Phase.FOLLOWING and task.plan is not None:
            self._follow(task, pose, now, dt, grid)
        elif task.phase in (Phase.BACKING_UP, Phase.CLEARING):
            self._recover(task, pose, now, grid)
        else:
            self._publish_cmd(0.0, 0.0)  # no path yet: hold still
        if self._task is task:
            if task.replan_wanted and not self._planning_in_flight and task.phase in (Phase.PLANNING, Phase.FOLLOWING):
                self._request_plan(task, now, urgent=True)
            self._feedback(task, pose, now)

    def _fresh_pose(self, task: _Task, now: float) -> Pose2D | None:
        """The robot's pose, or ``None`` (robot held, maybe goal aborted) when the pose is stale."""
        p = self._params
        age = self._tracker.pose_age_s(now)
        # map -> odom changes slowly: while fresh odometry carries the pose, a localiser running late
        # (a busy machine) is no reason to stop.
        if age <= p.pose_timeout_s or (age <= p.carried_pose_timeout_s and self._tracker.carried_by_odometry(now, p.pose_timeout_s)):
            if task.pose_lost_since_s is not None:
                self._log.info("pose is back: resuming")
            task.pose_lost_since_s = None
            return self._tracker.current_pose(now, self._params.pose_timeout_s)
        if task.pose_lost_since_s is None:
            task.pose_lost_since_s = now
            task.pose_lost_since_wall_s = time.monotonic()
            self._log.warning("no fresh %s (%.2f s old): holding still", topics.POSE2D, age)
        self._publish_cmd(0.0, 0.0)
        # Also on the wall clock: at 30x real time a pose pipeline lagging under load is not a lost pose.
        lost_s = min(now - task.pose_lost_since_s, time.monotonic() - task.pose_lost_since_wall_s)
        if lost_s > p.no_pose_timeout_s:
            self._finish(task, "aborted", NavigateErrorCode.NO_POSE,
                         f"no robot pose on {topics.POSE2D} for {p.no_pose_timeout_s:g} s")
        return None

    def _follow(self, task: _Task, pose: Pose2D, now: float, dt: float, grid: Any) -> None:
        p = self._params
        velocity = self._tracker.twist(now, self._params.pose_timeout_s) or self._last_cmd
        # Acceleration limits (and the lookahead) start from the last command, as Nav2's velocity smoother
        # does in open loop: measured odometry lags the base, and ramping from it would slow every start.
        reference = self._last_cmd if p.open_loop_acceleration else velocity
        command = self._follower.compute_velocity_command(pose, reference, dt, grid)
        if command.status is FollowStatus.GOAL_REACHED and (
            abs(velocity[0]) > p.trans_stopped_velocity_mps or abs(velocity[1]) > p.rot_stopped_velocity_radps
        ):
            # nav2's StoppedGoalChecker: inside the tolerances while still turning is not arrived. Brake
            # and judge again once stopped; an overshoot out of tolerance is then turned back.
            self._publish_cmd(0.0, 0.0)
            return
        if command.status is FollowStatus.GOAL_REACHED:
            self._log.info("goal reached at (%.3f, %.3f, %.3f) after %.1f s",
                           pose.x, pose.y, pose.yaw, now - task.started_s)
            self._finish(task, "succeeded", NavigateErrorCode.NONE, "")
            return
        if command.status is FollowStatus.COLLISION_AHEAD:
            self._publish_cmd(0.0, 0.0)
            if task.blocked_since_s is None:
                task.blocked_since_s = task.clock_s
                self._log.info("collision ahead: stopped, replanning")
            if task.clock_s - task.blocked_since_s > p.blocked_timeout_s:
                self._start_recovery(task, pose, NavigateErrorCode.STUCK,
                                     f"an obstacle blocked the way for {p.blocked_timeout_s:g} s")
            elif not self._follower.xy_goal_reached:
                self._request_plan(task, now, urgent=True)
            return
        task.blocked_since_s = None
        self._publish_cmd(command.linear_mps, command.angular_radps)
        if not task.progress.check(pose, task.clock_s):
            self._start_recovery(task, pose, NavigateErrorCode.STUCK,
                                 f"no progress for {p.progress_timeout_s:g} s")
            return
        assert task.plan is not None
        if (
            now - task.last_plan_request_s >= p.replan_period_s
            and not self._follower.xy_goal_reached
            and task.plan.remaining_m(self._follower.closest_index, pose) > NO_REPLAN_WITHIN_M
        ):
            self._request_plan(task, now)

    # --- recovery ---------------------------------------------------------------------------------

    def _start_recovery(self, task: _Task, pose: Pose2D, code: NavigateErrorCode, reason: str) -> None:
        p = self._params
        if task.recoveries >= p.max_recoveries:
            self._finish(task, "aborted", code, f"{reason} (gave up after {task.recoveries} recoveries)")
            return
        task.recoveries += 1
        task.recovering_from_planning = code in PLANNING_FAILURES
        self._log.warning("recovery %d of %d (%s): backing up, clearing, replanning",
                          task.recoveries, p.max_recoveries, reason)
        self._generation += 1
        task.generation = self._generation
        task.plan = None
        task.replan_wanted = False
        task.blocked_since_s = None
        self._follower.reset()
        task.phase = Phase.BACKING_UP
        self._backup.start(pose, task.clock_s)

    def _trust_turning_circle(self, now: float) -> None:
        """A task starts where the robot stands still: let it turn there (see
        :meth:`GlassMemory.observe_turning_circle`). Not for a goal that arrives while driving."""
        pose = self._tracker.current_pose(now, self._params.pose_timeout_s)
        velocity = self._tracker.twist(now, self._params.pose_timeout_s)
        if pose is None or velocity is None:
            return
        if abs(velocity[0]) > STANDING_STILL_MPS or abs(velocity[1]) > STANDING_STILL_RADPS:
            return
        self._layers.observe_turning_circle(pose)

    def _recover(self, task: _Task, pose: Pose2D, now: float, grid: Any) -> None:
        if task.phase is Phase.BACKING_UP:
            speed, status = self._backup.step(pose, task.clock_s, grid)
            if status is BackUpStatus.RUNNING:
                self._publish_cmd(speed, 0.0)
                return
            self._publish_cmd(0.0, 0.0)
            self._layers.clear(glass_clearing(task.recoveries, task.recovering_from_planning), pose)
            task.phase = Phase.CLEARING
            task.wait_until_s = task.clock_s + self._params.recovery_wait_s
            return
        self._publish_cmd(0.0, 0.0)
        if task.clock_s >= task.wait_until_s:
            task.phase = Phase.PLANNING
            self._request_plan(task, now)

    # --- feedback ---------------------------------------------------------------------------------

    def _feedback(self, task: _Task, pose: Pose2D, now: float) -> None:
        if now - task.last_feedback_s < 1.0 / self._params.feedback_rate_hz - 1e-6:
            return
        task.last_feedback_s = now
        if task.plan is not None:
            remaining = task.plan.remaining_m(self._follower.closest_index, pose)
        else:
            remaining = pose.distance_to(task.goal)
        velocity = self._tracker.twist(now, self._params.pose_timeout_s) or self._last_cmd
        speed = abs(velocity[0])
        eta = remaining / (speed if speed > ETA_MIN_SPEED_MPS else self._params.max_linear_vel_mps)
        task.handle.publish_feedback(NavigateToPoseFeedback(
            current_pose=PoseStamped(Header.at(now, topics.MAP_FRAME), Pose.from_pose2d(pose)),
            navigation_time=Duration.from_sec(max(0.0, now - task.started_s)),
            estimated_time_remaining=Duration.from_sec(eta),
            number_of_recoveries=task.recoveries,
            distance_remaining=remaining,
        ))

    # --- shutdown ---------------------------------------------------------------------------------

    def close(self) -> None:
        self._log.info("CPU per control tick: %s; per costmap update: %s", self._control_time.summary(),
                       self._costmap_time.summary())
        task = self._task
        if task is not None:
            self._finish(task, "aborted", NavigateErrorCode.UNKNOWN, "the planner is shutting down")
        for timer in self._timers:
            timer.cancel()
        self._worker.close()
        self._action.close()


def _add_flags(parser: Any) -> dict[str, str]:
    parser.add_argument("--map", default=None, help="map_server YAML file (same as -p map_yaml=FILE)")
    parser.add_argument("--world", default=None, help="world file rasterised into the map (same as -p world=FILE)")
    return {"map": "map_yaml", "world": "world"}


def main(argv: list[str] | None = None) -> int:
    return run_service(
        "planner", Params, PlannerService, argv,
        description="Navigation: map server, layered costmap, A* planner and regulated pure pursuit "
                    "behind the navigate_to_pose action.",
        add_flags=_add_flags,
    )
