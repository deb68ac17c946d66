"""The docking service's wiring: battery, pose, odometry, detections and range sensors in; cmd_vel,
planner goals, the dock_robot / undock_robot actions and ``docking/state`` out.

Everything runs on the node's executor (callbacks never overlap, nothing blocks): sensor callbacks
only store what arrives; one timer on the node's clock -- 20 Hz for the graceful controller, 10 Hz
for the seed controller -- builds a :class:`~services.docking.task_io.TickInputs` snapshot, lets the
:class:`~services.docking.mission.Mission` start what is due, steps the running task (a
:class:`~services.docking.docking_run.DockingRun`, an :class:`~services.docking.undocking_run.UndockingRun`
or a :class:`~services.docking.patrol.Patrol`) and carries out its intent through the
:class:`~services.docking.drive_arbiter.DriveArbiter`, so that the service and the planner never drive
at the same time. The low-battery trigger starts the same docking run as the action.

Charging is read from battery_status (CHARGING or FULL), as a real robot would; the simulator's ground
truth (dock_contact, ground_truth_pose) is never used.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace
from typing import Any

import numpy as np

from services.docking.dock_claim import AwaitDock, DockClaim, docks_seen_free
from services.docking.dock_db import DockDatabase, load_dock_db
from services.docking.dock_tracker import DockTracker
from services.docking.docking_run import DockingRun, DockRequest, RunPhase
from services.docking.drive_arbiter import DriveArbiter, DriveOrders
from services.docking.errors import DockingError, DockingState
from services.docking.ir_run import IR_MAX_AGE_S, IrDockingRun
from services.docking.mission import Mission, MissionMode, MissionOrder, TaskKind
from services.docking.params import Params
from services.docking.patrol import Patrol
from services.docking.peers import PeerWatch
from services.docking.pose_filter import PoseFilterParams
from services.docking.room_paths import RoomPaths
from services.docking.safety import ObstacleParams, lidar_blocked, scan_points, sonar_blocked
from services.docking.task_io import (
    Intent,
    Navigate,
    NavOutcome,
    NavStatus,
    Outcome,
    Task,
    TickInputs,
    Velocity,
)
from services.docking.traffic import TOO_CLOSE_CALM_S, GiveWay, Meeting, must_give_way, passing_place
from services.docking.undocking_run import UndockingRun
from shared import topics
from shared.action import ActionServer, ServerGoalHandle
from shared.config_errors import ConfigError
from shared.fleet_client import FleetAnswer, FleetClient
from shared.frames import SensorMounts, clock_went_back
from shared.geometry import Pose2D
from shared.interfaces.docking import (
    DOCK_ROBOT,
    UNDOCK_ROBOT,
    DockRobotFeedback,
    DockRobotGoal,
    DockRobotResult,
    UndockRobotFeedback,
    UndockRobotGoal,
    UndockRobotResult,
)
from shared.messages import (
    BatteryState,
    DockInfraRed,
    Duration,
    Float64MultiArray,
    LaserScan,
    Odometry,
    PoseStamped,
    Range,
    String,
    TFMessage,
    Twist,
)
from shared.navigation import NavigationClient, TaskResult
from shared.node import RELIABLE, SENSOR_DATA, Node, QoS, ServiceError, Subscription
from shared.pose_tracking import OdometrySample, PoseTrack
from shared.ratelimit import RateLimitedLogger
from shared.runtime import ServiceSpec
from shared.world import World, load_world

#: std_msgs/String with the service's state name, for tools (published on change and every second).
DOCKING_STATE = "docking/state"
#: Control rates fixed by the controllers: graceful 20 Hz, seed (line approach) 10 Hz.
CONTROL_PERIOD_S = {"graceful": 0.05, "seed": 0.1, "ir": 0.05}
#: A sensor reading older than this is ignored by the obstacle checks.
SENSOR_MAX_AGE_S = 0.5
STATE_PERIOD_S = 1.0
#: Detections stay subscribed this long (sim seconds) after the run last wanted them.
DETECTION_LINGER_S = 1.0
_CHARGING = (BatteryState.POWER_SUPPLY_STATUS_CHARGING, BatteryState.POWER_SUPPLY_STATUS_FULL)


def _room_world(dock_database: str) -> World | None:
    """The world the dock database is, when it is a world file (a fleet's room); None for a plain one."""
    try:
        return load_world(dock_database)
    except ConfigError:
        return None


class DockingService:
    """The docking service on a node; see the module docstring."""

    def __init__(self, node: Node, params: Params) -> None:
        self.node = node
        self.params = params
        self._log = node.log
        self._say = RateLimitedLogger(node.log, interval_s=5.0)
        self.database: DockDatabase = load_dock_db(params.dock_database)
        self.track = PoseTrack()
        self.arbiter = DriveArbiter()
        self.obstacles = ObstacleParams(stop_distance_m=params.obstacle_stop_distance_m)
        #: The room, when the dock database is a world file: the robot's patrol, the walls for the traffic
        #: rule's passing places and the path lengths to the docks.
        room = _room_world(params.dock_database) if params.fleet or not params.patrol else None
        name = node.namespace.rpartition("/")[2]
        patrol = params.patrol or (next((list(r.patrol) for r in room.robots if r.name == name), [])
                                   if room is not None and name else [])
        self.mission = Mission(
            [Pose2D.from_seq(p) for p in patrol], params.resume_at, params.low_battery_threshold,
            params.auto_dock,
        )
        self.task: Task[Any] | None = None
        self.task_kind: TaskKind | None = None
        self.task_handle: ServerGoalHandle[Any, Any, Any] | None = None
        self._battery: BatteryState | None = None
        self._battery_received_s = -math.inf
        self._scan_points: np.ndarray | None = None
        self._scan_received_s = -math.inf
        self._sonar_range_m = math.inf
        self._sonar_received_s = -math.inf
        self._mounts = SensorMounts()
        #: The map -> odom correction the running docking run's detections were last moved to.
        self._applied_correction: Pose2D | None = None
        self._last_now_s = -math.inf
        self._holding = ""
        self._last_state = ""
        self._state_published_s = -math.inf
        self._feedback_key: tuple[int, int] | None = None
        self._feedback_published_s = -math.inf
        #: Robots sharing docks ask the fleet service one namespace up (``r1`` asks ``fleet/...``).
        self.claim = DockClaim(patience_s=params.fleet_patience_s) if params.fleet else None
        self.fleet = FleetClient(node)
        #: The room's walls, for passing places (the traffic rule) and path lengths to the docks.
        self._walls = [*room.opaque_segments(), *room.glass] if params.fleet and room is not None else []
        #: Path lengths to the docks through the room, for the fleet's "nearest free dock".
        self._room = RoomPaths(room.bounds, self._walls) if self._walls and room is not None else None
        self._approach = params.approach_controller()
        #: The fleet's other robots, for the traffic rule (and until when not to stop again for one too close).
        self.peers = PeerWatch(node, DOCKING_STATE) if self._walls else None
        self._calm_until: dict[str, float] = {}

        self.cmd_vel = node.create_publisher(Twist, topics.CMD_VEL, RELIABLE)
        self.state_pub = node.create_publisher(String, DOCKING_STATE, RELIABLE)
        self.nav = NavigationClient(node)
        node.create_subscription(BatteryState, topics.BATTERY_STATUS, self._on_battery, QoS(depth=5))
        node.create_subscription(Float64MultiArray, topics.POSE2D, self._on_pose, QoS(depth=5))
        node.create_subscription(Odometry, topics.ODOM, self._on_odom, SENSOR_DATA)
        #: Declared only while a docking run wants detections: the perception service sees no subscriber
        #: otherwise, stops reading images, and the simulator stops rendering them.
        self._detection_sub: Subscription[PoseStamped] | None = None
        self._detections_wanted_s = -math.inf
        node.create_subscription(LaserScan, topics.SCAN, self._on_scan, SENSOR_DATA)
        node.create_subscription(Range, topics.ULTRASONIC, self._on_sonar, SENSOR_DATA)
        node.create_subscription(TFMessage, topics.TF_STATIC, self._on_tf_static, QoS(depth=20))
        self._ir_dock: tuple[int, int, int] | None = None
        self._ir_received_s = -math.inf
        if params.controller == "ir":
            node.create_subscription(DockInfraRed, topics.IR_DOCK, self._on_ir_dock, SENSOR_DATA)
        self.dock_server = ActionServer(
            node, DOCK_ROBOT, topics.DOCK_ROBOT, on_goal=self._check_dock_goal, on_accepted=self._on_dock_goal,
            on_cancel=self._on_cancel, preempt_result=lambda: DockRobotResult(success=False),
        )
        self.undock_server = ActionServer(
            node, UNDOCK_ROBOT, topics.UNDOCK_ROBOT, on_goal=self._check_undock_goal,
            on_accepted=self._on_undock_goal, on_cancel=self._on_cancel,
            preempt_result=lambda: UndockRobotResult(success=False),
        )
        self.period_s = CONTROL_PERIOD_S[params.controller]
        self.timer = node.create_timer(self.period_s, self._on_tick)
        self._log.info(
            "controller %s at %g Hz, %d dock(s) from %s, detection %s, patrol of %d waypoint(s), on %s time%s",
            params.controller, 1.0 / self.period_s, len(self.database), params.dock_database,
            "on" if params.use_detection else "off", len(patrol), "sim" if node.use_sim_time else "wall",
            f", docks reserved with {self.fleet.reserve_key}" if params.fleet else "",
        )

    # --- inputs ------------------------------------------------------------------------------------

    def _on_battery(self, msg: BatteryState) -> None:
        self._battery = msg
        self._battery_received_s = self.node.now()
        charging = msg.power_supply_status in _CHARGING
        if self.mission.battery(msg.percentage, charging):
            self._log.info("battery at %.1f%%, below %.0f%%: going home", 100.0 * msg.percentage,
                          100.0 * self.params.low_battery_threshold)

    def _on_pose(self, msg: Float64MultiArray) -> None:
        data = msg.data
        if len(data) < 3 or not np.all(np.isfinite(data[:3])):
            self._say.warning("pose", "ignored a %s message without a finite [x, y, yaw]", topics.POSE2D)
            return
        self.track.add_pose(self.node.now(), Pose2D.from_seq(data[:3]), self.params.pose_latency_s)

    def _on_odom(self, msg: Odometry) -> None:
        twist = msg.twist.twist
        # An odometry jump (the robot was moved) makes the track ignore localisation for a while: the
        # localiser may still report where the robot was.
        self.track.add_odom(
            OdometrySample(msg.header.stamp.to_sec(), msg.pose.pose.to_pose2d(), twist.linear.x, twist.angular.z),
            self.node.now(),
        )

    def _want_detections(self, wanted: bool, now_s: float) -> None:
        """Subscribe to detections while the run wants them (and a little longer, so no flapping)."""
        if wanted:
            self._detections_wanted_s = now_s
        if wanted and self._detection_sub is None:
            self._detection_sub = self.node.create_subscription(PoseStamped, topics.DETECTED_DOCK_POSE,
                                                                self._on_detection, SENSOR_DATA)
        elif (not wanted and self._detection_sub is not None
              and not 0.0 <= now_s - self._detections_wanted_s < DETECTION_LINGER_S):
            self._detection_sub.undeclare()
            self._detection_sub = None

    def _on_detection(self, msg: PoseStamped) -> None:
        task = self.task
        if not isinstance(task, DockingRun):
            return
        if msg.header.frame_id not in ("", topics.BASE_FRAME):
            self._say.warning("detection-frame", "ignored a dock detection in frame %r (expected %s)",
                              msg.header.frame_id, topics.BASE_FRAME)
            return
        stamp_s = msg.header.stamp.to_sec()
        self._follow_correction()
        robot_at_stamp = self.track.pose_now_at(stamp_s)
        if robot_at_stamp is None:
            self._say.info("detection-pose", "no robot pose at a detection's stamp %.3f s: ignored", stamp_s)
            return
        task.add_detection(msg.pose.to_pose2d(), robot_at_stamp, stamp_s)

    def _on_scan(self, msg: LaserScan) -> None:
        lidar_mount = self._mounts.get(topics.LIDAR_FRAME)
        if lidar_mount is None:
            return
        self._scan_points = scan_points(msg.ranges, msg.angle_min, msg.angle_increment, lidar_mount)
        self._scan_received_s = self.node.now()

    def _on_sonar(self, msg: Range) -> None:
        self._sonar_range_m = float(msg.range)
        self._sonar_received_s = self.node.now()

    def _on_ir_dock(self, msg: DockInfraRed) -> None:
        if msg.data.size != 3:
            self._say.warning("ir-dock", "ignored an ir_dock message with %d readings (expected right, central, left)",
                              msg.data.size)
            return
        self._ir_dock = (int(msg.data[0]), int(msg.data[1]), int(msg.data[2]))
        self._ir_received_s = self.node.now()

    def _on_tf_static(self, msg: TFMessage) -> None:
        self._mounts.update(msg)

    def _follow_correction(self) -> None:
        """Move the detected dock with every change of the localiser's map -> odom correction, so that it
        stays where odometry put it relative to the robot (see :mod:`services.docking.dock_tracker`)."""
        correction = self.track.map_to_odom
        applied = self._applied_correction
        if isinstance(self.task, DockingRun) and correction is not None and applied is not None and correction != applied:
            self.task.relocalised(correction.compose(applied.inverse()))
        self._applied_correction = correction

    def _charging(self, now_s: float) -> bool:
        fresh = self._battery is not None and now_s - self._battery_received_s <= self.params.battery_timeout_s
        return fresh and self._battery is not None and self._battery.power_supply_status in _CHARGING

    def _nav_status(self) -> NavStatus:
        busy = not self.nav.is_task_complete()
        outcome: NavOutcome | None = None
        if not busy and self.arbiter.nav_key is not None:
            outcome = {
                TaskResult.SUCCEEDED: NavOutcome.SUCCEEDED,
                TaskResult.CANCELED: NavOutcome.CANCELED,
            }.get(self.nav.get_result(), NavOutcome.FAILED)
        return NavStatus(self.arbiter.nav_key, busy, outcome, self.nav.failure_reason() if outcome else "")

    def _inputs(self, now_s: float) -> TickInputs:
        robot_pose: Pose2D | None = None
        pose_age_s = 0.0
        if self.track.pose_fresh(now_s, self.params.max_pose_age_s, self.params.max_localisation_age_s):
            latest = self.track.latest()
            if latest is not None:
                pose_stamp_s, robot_pose = latest
                pose_age_s = max(0.0, now_s - pose_stamp_s)
        blocked_ahead = blocked_behind = False
        if robot_pose is not None and isinstance(self.task, (DockingRun, UndockingRun)):
            dock = self.task.dock_pose
            dock_in_base = dock.relative_to(robot_pose) if dock is not None else None
            blocked_ahead, blocked_behind = self._blocked(now_s, dock_in_base)
        elif isinstance(self.task, IrDockingRun):
            blocked_ahead, blocked_behind = self._blocked(now_s, None)  # no map pose: nothing is the dock
        return TickInputs(
            now_s=now_s,
            robot_pose=robot_pose,
            pose_age_s=pose_age_s,
            base_twist=self.track.twist(now_s, SENSOR_MAX_AGE_S),
            charging=self._charging(now_s),
            nav=self._nav_status(),
            blocked_ahead=blocked_ahead,
            blocked_behind=blocked_behind,
            ir_dock=self._ir_dock if now_s - self._ir_received_s <= IR_MAX_AGE_S else None,
        )

    def _blocked(self, now_s: float, dock_in_base: Pose2D | None) -> tuple[bool, bool]:
        ahead = behind = False
        p = self.params
        if p.use_lidar and self._scan_points is not None and now_s - self._scan_received_s <= SENSOR_MAX_AGE_S:
            ahead = lidar_blocked(self._scan_points, True, dock_in_base, self.obstacles)
            # Reversing never goes towards the dock: nothing behind is excused.
            behind = lidar_blocked(self._scan_points, False, None, self.obstacles)
        if p.use_sonar and now_s - self._sonar_received_s <= SENSOR_MAX_AGE_S:
            ahead = ahead or sonar_blocked(self._sonar_range_m, dock_in_base, self.obstacles)
        return ahead, behind

    # --- the tick ----------------------------------------------------------------------------------

    def _on_tick(self) -> None:
        now = self.node.now()
        if clock_went_back(now, self._last_now_s):
            self._log.warning("clock jumped back to %.3f s (a reset?): forgetting the pose history and what runs", now)
            self.track.clear()
            self.mission.trigger.reset()  # a low battery after the reset sends the robot home again
            if self.task is not None:
                self.task.cancel()
        self._last_now_s = now
        self._follow_mission(now)
        if self.claim is not None:
            self._follow_fleet(now)
        if self.peers is not None:
            self._follow_traffic(now, self.peers)
        task = self.task
        if isinstance(task, DockingRun):
            latest = self.track.latest()
            self._want_detections(task.wants_detections(latest[1] if latest is not None else None), now)
        else:
            self._want_detections(False, now)
        if task is not None:
            self._follow_correction()
            inputs = self._inputs(now)
            intent = task.step(inputs)
            if task.holding and task.holding != self._holding:
                self._say.info(f"hold:{task.holding}", "holding still: %s", task.holding)
            if task.holding and self._log.isEnabledFor(logging.DEBUG):
                odom = self.track.latest_odom
                self._log.debug("hold t=%.3f %s: localisation %.3f s old, odometry %s", now, task.holding,
                               now - self.track.last_pose_received_s,
                               f"{now - odom.stamp_s:.3f} s old" if odom else "none")
            self._holding = task.holding
            self._carry_out(intent, inputs)
            self._publish_feedback(now)
            if task.done:
                self._end_task()
        self._publish_state(now)

    def _follow_mission(self, now: float) -> None:
        order = self.mission.decide(now, self.task_kind)
        if order is MissionOrder.DOCK:
            self._begin_docking(DockRequest(dock_id=self.params.dock_id,
                                            max_staging_time_s=self.params.max_staging_time_s), None)
        elif order is MissionOrder.UNDOCK:
            self._log.info("charged to %.0f%%: undocking to resume the patrol", 100.0 * self.mission.percentage)
            self._start(self._undocking_run(UndockRobotGoal().max_undocking_time, ""), TaskKind.UNDOCK)
        elif order is MissionOrder.PATROL:
            self._log.info("patrolling from waypoint %d", self.mission.next_waypoint)
            self._start(Patrol(self.mission.patrol, self.mission.next_waypoint), TaskKind.PATROL)

    # --- the fleet ---------------------------------------------------------------------------------

    def _begin_docking(self, request: DockRequest, handle: ServerGoalHandle[Any, Any, Any] | None) -> None:
        """Dock now, or (sharing docks) once the fleet grants one: wait in :class:`AwaitDock` till then."""
        claim = self.claim
        if claim is None or request.dock_pose is not None:
            self._start(self._docking_run(request), TaskKind.DOCK, handle)
            return
        now = self.node.now()
        claim.want(now, request.dock_id)
        granted = claim.granted_dock
        if granted is not None:
            self._start(self._docking_run(replace(request, dock_id=granted)), TaskKind.DOCK, handle)
        else:
            self._log.info("asking the fleet for %s", f"dock {request.dock_id!r}" if request.dock_id else "a dock")
            self._start(AwaitDock(request), TaskKind.DOCK, handle)

    def _follow_fleet(self, now: float) -> None:
        """Ask, renew and release as due; start docking once a dock is granted (or seen free, the fleet down)."""
        claim = self.claim
        assert claim is not None
        task = self.task
        if isinstance(task, AwaitDock):
            granted = claim.granted_dock
            if granted is not None:
                self._log.info("the fleet granted dock %s", granted)
                self._start(self._docking_run(replace(task.request, dock_id=granted)), TaskKind.DOCK, self.task_handle)
            elif claim.fleet_down(now):
                self._dock_without_fleet(task, now)
        elif task is None and claim.granted_dock is None and self._charging(now) and not claim.release_pending:
            # In a dock without a claim (started there, or the fleet lost its book): claim the dock it is in.
            latest = self.track.latest()
            if latest is not None:
                claim.holds(now, self.database.nearest(latest[1]).id)
        if claim.asked_to_leave and self.mission.leave_dock():
            self._log.info("the fleet asks this robot to leave its dock for a robot whose battery is critical")
        if claim.reserve_due(now):
            self._ask_fleet(now)
        elif claim.release_due(now):
            claim.sent(now)
            self.fleet.release(on_done=self._on_released)

    def _ask_fleet(self, now: float) -> None:
        claim = self.claim
        assert claim is not None
        battery = self._battery.percentage if self._battery is not None else math.nan
        if not 0.0 <= battery <= 1.0:
            return  # the fleet serves by charge: ask once the battery has spoken
        latest = self.track.latest()
        lengths: dict[str, float] | None = None
        if latest is not None and claim.granted_dock is None:
            lengths = self._dock_distances(latest[1])
        claim.sent(now)
        self.fleet.reserve(battery, claim.dock_id, lengths, on_answer=self._on_reserved)

    def _dock_distances(self, robot: Pose2D) -> dict[str, float]:
        """How far each dock is to drive to (the fleet grants the nearest free one): through the room to its
        staging pose and on into the dock, or (a plain dock database, no room) in a straight line."""
        docks = {d.id: d.pose2d for d in self.database}
        if self._room is None:
            return {dock_id: robot.distance_to(pose) for dock_id, pose in docks.items()}
        staging = [self._approach.staging_pose(pose) for pose in docks.values()]
        found = self._room.lengths(robot, staging)
        return {dock_id: length + stage.distance_to(pose)
                for (dock_id, pose), stage, length in zip(docks.items(), staging, found, strict=True)}

    def _on_reserved(self, answer: FleetAnswer | None, error: ServiceError | None) -> None:
        claim = self.claim
        assert claim is not None
        now = self.node.now()
        if answer is None:
            claim.unanswered(now)
            self._say.warning("fleet", "the fleet did not answer: %s", error)
            return
        if answer.refused:
            self._say.warning("fleet-refused", "the fleet refused: %s", answer.reason)
        claim.answered(now, answer)
        if isinstance(self.task, AwaitDock) and not answer.granted:
            if answer.queue_position:
                self._say.info("queued", "waiting for a dock: number %d in the queue (%s)",
                               answer.queue_position, answer.reason)
            self.task.hold_at(answer.holding_pose)

    def _on_released(self, dock_id: str | None, error: ServiceError | None) -> None:
        claim = self.claim
        assert claim is not None
        if dock_id is None:
            claim.unanswered(self.node.now())
            self._say.warning("fleet", "the fleet did not answer a release: %s", error)
            return
        claim.released(self.node.now())
        if dock_id:
            self._log.info("released dock %s", dock_id)

    def _dock_without_fleet(self, task: AwaitDock, now: float) -> None:
        """The fleet is down: dock at the nearest dock seen free (no robot in it), keeping it as a claim so
        the fleet learns of it when it is back."""
        claim = self.claim
        latest = self.track.latest()
        if claim is None or latest is None:
            return
        fresh = self._scan_points if now - self._scan_received_s <= SENSOR_MAX_AGE_S else None
        wanted = task.request.dock_id
        docks = [(d.id, d.pose2d) for d in self.database if not wanted or d.id == wanted]
        free = docks_seen_free(docks, latest[1], fresh)
        if not free:
            self._say.warning("fleet-down", "the fleet is down and no dock is seen free: waiting")
            return
        self._log.warning("the fleet has not answered for %g s: docking at %s, seen free", claim.patience_s, free[0])
        claim.holds(now, free[0])
        self._start(self._docking_run(replace(task.request, dock_id=free[0])), TaskKind.DOCK, self.task_handle)

    # --- traffic -----------------------------------------------------------------------------------

    def _under_way(self) -> bool:
        task = self.task
        return (isinstance(task, Patrol) or (isinstance(task, DockingRun) and task.phase is RunPhase.NAV_TO_STAGING)
                or (isinstance(task, AwaitDock) and task.going))

    def _follow_traffic(self, now: float, peers: PeerWatch) -> None:
        """Give way to a robot with priority met head-on (see :mod:`services.docking.traffic`)."""
        task = self.task
        if isinstance(task, GiveWay):
            task.peer_seen(*peers.seen(task.peer, now))
            return
        if not self._under_way() or self._battery is None:
            return
        latest = self.track.latest()
        if latest is None:
            return
        me = latest[1]
        calm = {peer for peer, until in self._calm_until.items() if now < until}
        met = must_give_way(me, self.node.namespace, float(self._battery.percentage), peers.fresh(now), self._walls,
                            calm)
        if met is None:
            return
        peer, meeting = met
        place: Pose2D | None = None
        if meeting is Meeting.HEAD_ON:
            place = passing_place(me, peer, self._walls)
            if place is None:
                self._say.warning("no-passing-place", "met %s head-on and must give way, but found no passing place: "
                                  "stopping", peer.name)
        if place is not None:
            self._log.info("met %s head-on (it has priority): giving way at (%.2f, %.2f)", peer.name, place.x, place.y)
        elif meeting is Meeting.HEAD_ON_PRIORITY:
            self._log.info("met %s head-on (this robot has priority): waiting for it to back out", peer.name)
        elif meeting is Meeting.TOO_CLOSE:
            self._log.info("%s is too close in front: stopping for a moment", peer.name)
            self._calm_until[peer.name] = now + TOO_CLOSE_CALM_S
        else:
            self._log.info("%s crosses this robot's way (it has priority): stopping for it", peer.name)
        resume = task.request if isinstance(task, (DockingRun, AwaitDock)) else None
        assert self.task_kind is not None
        self._start(GiveWay(peer, meeting, place, resume), self.task_kind, self.task_handle)

    def _carry_out(self, intent: Intent, inputs: TickInputs) -> None:
        if isinstance(intent, Velocity):
            orders = self.arbiter.velocity(intent, inputs.nav.busy, inputs.now_s)
        elif isinstance(intent, Navigate):
            orders = self.arbiter.navigate(intent)
        else:
            orders = DriveOrders()
        self._apply(orders)

    def _apply(self, orders: DriveOrders) -> None:
        if orders.cancel_nav:
            self.nav.cancel_task()
        if orders.publish is not None:
            if not self.nav.is_task_complete():
                # The arbiter never allows this; a stop is still better than nothing if it ever happens.
                self._say.error("overlap", "publishing cmd_vel while the planner holds a goal")
            self.cmd_vel.publish(Twist.planar(orders.publish.linear_x_mps, orders.publish.angular_z_radps))
        if orders.send_goal is not None:
            self.nav.go_to_pose(orders.send_goal)

    # --- tasks -------------------------------------------------------------------------------------

    def _docking_run(self, request: DockRequest) -> DockingRun | IrDockingRun:
        p = self.params
        if p.controller == "ir":
            latest = self.track.latest()
            robot = latest[1] if latest is not None else None
            try:
                dock = request.dock_pose or self.database.choose(request.dock_id or None, robot,
                                                                 request.dock_type or None).pose2d
            except DockingError:
                dock = None  # no such dock in the database: infrared docking needs none
            return IrDockingRun(max_time_s=min(p.max_docking_time_s, p.approach_timeout_s + 60.0), dock_pose=dock,
                                staging_offset_m=p.staging_offset_m, max_staging_time_s=request.max_staging_time_s)
        tracker = DockTracker(replace(PoseFilterParams(), coef=p.detection_filter_coef), p.max_detection_offset_m)
        return DockingRun(request, self.database, p.approach_controller(), p.docking_config(), tracker)

    def _undocking_run(self, max_time_s: float, dock_type: str) -> UndockingRun:
        return UndockingRun(self.database, max_time_s, dock_type, self.params.undock_config())

    def _start(self, task: Task[Any], kind: TaskKind,
               handle: ServerGoalHandle[Any, Any, Any] | None = None) -> None:
        """Run ``task`` from the next tick on, replacing whatever runs (its action, if any, is cancelled)."""
        old, old_handle = self.task, self.task_handle
        if isinstance(old, Patrol):
            self.mission.next_waypoint = old.next_index
        if old_handle is not None and old_handle.active and old_handle is not handle:
            old_handle.canceled(self._result_message(old_handle, None))
        if isinstance(old, AwaitDock) and kind is not TaskKind.DOCK and self.claim is not None:
            self.claim.drop()  # no longer waiting for a dock
        if old is not None:
            self._log.info("%s replaced by %s", type(old).__name__, type(task).__name__)
        self.task, self.task_kind, self.task_handle = task, kind, handle
        self._feedback_key = None

    def _end_task(self) -> None:
        task, kind, handle = self.task, self.task_kind, self.task_handle
        assert task is not None and task.result is not None and kind is not None
        result = task.result
        self.task, self.task_kind, self.task_handle = None, None, None
        self._holding = ""
        self._apply(self.arbiter.release())
        if isinstance(task, Patrol):
            self.mission.next_waypoint = task.next_index
        if isinstance(task, GiveWay):
            self._log.info("gave way: %s", task.message or "done")
            if isinstance(task.resume, DockRequest):
                self._begin_docking(task.resume, handle)  # carry on docking (a patrol the mission restarts)
            return
        self.mission.finished(kind, result.success, handle is not None, self.node.now())
        if self.claim is not None and ((kind is TaskKind.DOCK and not result.success)
                                       or (kind is TaskKind.UNDOCK and result.success)):
            self.claim.drop()  # out of the dock (or never got in): the dock is free for others
        level = logging.INFO if result.outcome is not Outcome.FAILED else logging.WARNING
        took = (f" after {task.docking_time_s(self.node.now()):.1f} s" if isinstance(task, (DockingRun, IrDockingRun))
                else "")
        self._log.log(level, "%s %s%s (code %d, %d retries)%s", kind.value, result.outcome.value, took,
                     int(result.error_code), result.num_retries, f": {result.message}" if result.message else "")
        if handle is None or not handle.active:
            return
        message = self._result_message(handle, task)
        if result.outcome is Outcome.SUCCEEDED:
            handle.succeed(message)
        elif result.outcome is Outcome.CANCELED:
            handle.canceled(message)
        else:
            handle.abort(message)

    @staticmethod
    def _result_message(handle: ServerGoalHandle[Any, Any, Any], task: Task[Any] | None) -> Any:
        result = task.result if task is not None else None
        success = result is not None and result.success
        code = int(result.error_code) if result is not None else 0
        if isinstance(handle.goal, DockRobotGoal):
            return DockRobotResult(success=success, error_code=code, num_retries=task.retries if task else 0)
        return UndockRobotResult(success=success, error_code=code)

    # --- actions -----------------------------------------------------------------------------------

    def _check_dock_goal(self, goal: DockRobotGoal) -> None:
        if not goal.use_dock_id and goal.dock_pose.header.frame_id not in ("", topics.MAP_FRAME):
            raise ValueError(f"dock_pose must be in the {topics.MAP_FRAME} frame, got {goal.dock_pose.header.frame_id!r}")
        if not goal.max_staging_time > 0.0:
            raise ValueError(f"max_staging_time must be > 0, got {goal.max_staging_time}")

    def _on_dock_goal(self, handle: ServerGoalHandle[DockRobotGoal, DockRobotResult, DockRobotFeedback]) -> None:
        if not handle.active:
            return
        goal = handle.goal
        handle.execute()
        request = DockRequest(
            dock_id=goal.dock_id if goal.use_dock_id else "",
            dock_pose=None if goal.use_dock_id else goal.dock_pose.pose.to_pose2d(),
            dock_type=goal.dock_type,
            navigate_to_staging_pose=goal.navigate_to_staging_pose,
            max_staging_time_s=goal.max_staging_time,
        )
        self._log.info("dock_robot: %s", f"dock {goal.dock_id!r}" if goal.use_dock_id and goal.dock_id
                      else "the nearest dock" if goal.use_dock_id else "a given pose")
        self._begin_docking(request, handle)

    def _check_undock_goal(self, goal: UndockRobotGoal) -> None:
        if not goal.max_undocking_time > 0.0:
            raise ValueError(f"max_undocking_time must be > 0, got {goal.max_undocking_time}")

    def _on_undock_goal(self, handle: ServerGoalHandle[UndockRobotGoal, UndockRobotResult, UndockRobotFeedback]) -> None:
        if not handle.active:
            return
        handle.execute()
        self._log.info("undock_robot")
        self._start(self._undocking_run(handle.goal.max_undocking_time, handle.goal.dock_type), TaskKind.UNDOCK,
                    handle)

    def _on_cancel(self, handle: ServerGoalHandle[Any, Any, Any]) -> None:
        if handle is self.task_handle and self.task is not None:
            self._log.info("%s: cancel requested", type(self.task).__name__)
            self.task.cancel()
        elif handle.active:
            handle.canceled(self._result_message(handle, None))

    # --- status ------------------------------------------------------------------------------------

    def _publish_feedback(self, now: float) -> None:
        task, handle = self.task, self.task_handle
        if not isinstance(task, (DockingRun, IrDockingRun)) or handle is None or not handle.active:
            return
        key = (int(task.feedback_state), task.num_retries)
        if key == self._feedback_key and now - self._feedback_published_s < self.params.feedback_period_s:
            return
        self._feedback_key, self._feedback_published_s = key, now
        handle.publish_feedback(DockRobotFeedback(
            state=int(task.feedback_state),
            docking_time=Duration.from_sec(max(0.0, task.docking_time_s(now))),
            num_retries=task.num_retries,
        ))

    def state_name(self) -> str:
        """What the service is doing, for ``docking/state``."""
        task = self.task
        if isinstance(task, (DockingRun, IrDockingRun)):
            return task.feedback_state.name if task.feedback_state is not DockingState.NONE else "STARTING"
        if isinstance(task, UndockingRun):
            return "UNDOCKING"
        if isinstance(task, Patrol):
            return "PATROLLING"
        if isinstance(task, AwaitDock):
            return "WAITING_FOR_DOCK"
        if isinstance(task, GiveWay):
            return "GIVING_WAY"
        if self._charging(self.node.now()):
            return "DOCKED"
        return "HOLDING" if self.mission.mode is MissionMode.HOLDING else "IDLE"

    def _publish_state(self, now: float) -> None:
        name = self.state_name()
        if name == self._last_state and now - self._state_published_s < STATE_PERIOD_S:
            return
        if name != self._last_state:
            self._log.info("state %s (clock %.2f s)", name, now)
        self._last_state, self._state_published_s = name, now
        self.state_pub.publish(String(name))

    def close(self) -> None:
        self.timer.cancel()
        if self.task is not None:
            self.task.cancel()
        if not self.nav.is_task_complete():
            self.nav.cancel_task()
        if self.arbiter.moving:
            self.cmd_vel.publish(Twist.planar(0.0, 0.0))
        self.dock_server.close()
        self.undock_server.close()


SERVICE = ServiceSpec("docking", Params, DockingService,
                      description="zendock docking: goes home to charge when the battery runs low; "
                                  "dock_robot and undock_robot")


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)

