"""The docking service's wiring: battery, pose, odometry, detections and range sensors in; cmd_vel,
planner goals, fleet requests, the dock_robot / undock_robot actions and ``docking/state`` out.

Everything runs on the node's executor (callbacks never overlap, nothing blocks). Sensor callbacks only
store into the :class:`~services.docking.inputs.InputCache`; one timer on the node's clock -- 20 Hz for
the graceful and infrared controllers, 10 Hz for the seed controller -- hands its snapshot to the
:class:`~services.docking.executive.Executive`, and action goals, cancels and the fleet's answers go to
it as events at once; the end of a planner goal runs a tick at once. The node only carries out the
effects it returns. The low-battery trigger starts the same docking run as the action.

Charging is read from battery_status (CHARGING or FULL), as a real robot would; the simulator's ground
truth (dock_contact, ground_truth_pose) is never used.
"""

from __future__ import annotations

import logging
from typing import Any

from services.docking.dock_db import load_dock_db
from services.docking.docking_run import DockRequest
from services.docking.drive_arbiter import Hold
from services.docking.events import (
    CancelGoal,
    DockGoal,
    Drive,
    Effects,
    Event,
    FleetReleased,
    FleetReserved,
    Goal,
    GoalEnded,
    GoalFeedback,
    Log,
    PublishState,
    Release,
    Reserve,
    UndockGoal,
    WantDetections,
)
from services.docking.executive import Executive
from services.docking.heard import CHARGING_STATUSES, Heard, NavHeard
from services.docking.inputs import DockSightings, InputCache
from services.docking.mission import TaskKind
from services.docking.params import Params
from services.docking.peers import PeerWatch
from services.docking.task_io import NavOutcome, Outcome
from shared import topics
from shared.action import ActionServer, ServerGoalHandle
from shared.config_errors import ConfigError
from shared.fleet_client import FleetClient
from shared.frames import clock_went_back
from shared.interfaces.docking import (
    DOCK_ROBOT,
    UNDOCK_ROBOT,
    DockRobotGoal,
    DockRobotResult,
    UndockRobotGoal,
    UndockRobotResult,
)
from shared.messages import (
    BatteryState,
    DockInfraRed,
    Float64MultiArray,
    Header,
    LaserScan,
    Odometry,
    PacingHold,
    Range,
    String,
    TFMessage,
    Twist,
)
from shared.navigation import NavigationClient, TaskResult
from shared.node import RELIABLE, SENSOR_DATA, Node, QoS
from shared.ratelimit import RateLimitedLogger
from shared.runtime import ServiceSpec
from shared.world import World, load_world

#: std_msgs/String with the service's state name, for tools (published on change and every second).
DOCKING_STATE = "docking/state"
_NAV_OUTCOMES = {TaskResult.SUCCEEDED: NavOutcome.SUCCEEDED, TaskResult.CANCELED: NavOutcome.CANCELED}

GoalHandle = ServerGoalHandle[Any, Any, Any]


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
        database = load_dock_db(params.dock_database)
        #: The room, when the dock database is a world file: the robot's patrol, the walls for the traffic
        #: rule's passing places and the path lengths to the docks.
        room = _room_world(params.dock_database) if params.fleet or not params.patrol else None
        self.executive = Executive(params, database, room, node.namespace)
        self.executive.debug = node.log.isEnabledFor(logging.DEBUG)
        self.inputs = InputCache(params, self._say)
        self._last_now_s = float("-inf")

        self.cmd_vel = node.create_publisher(Twist, topics.CMD_VEL, RELIABLE)
        self.pacing_hold = node.create_publisher(PacingHold, topics.PACING_HOLD, RELIABLE)
        self.state_pub = node.create_publisher(String, DOCKING_STATE, RELIABLE)
        self.nav = NavigationClient(node)
        #: Robots sharing docks ask the fleet service one namespace up (``r1`` asks ``fleet/...``).
        self.fleet = FleetClient(node)
        #: The fleet's other robots, for the traffic rule.
        self.peers = PeerWatch(node, DOCKING_STATE) if self.executive.watches_traffic else None
        cache = self.inputs
        node.create_subscription(BatteryState, topics.BATTERY_STATUS, self._on_battery, QoS(depth=5))
        node.create_subscription(
            Float64MultiArray, topics.POSE2D, lambda m: cache.pose(m.data, node.now()), QoS(depth=5)
        )
        node.create_subscription(Odometry, topics.ODOM, lambda m: cache.odometry(m, node.now()), SENSOR_DATA)
        node.create_subscription(
            LaserScan,
            topics.SCAN,
            lambda m: cache.scan(m.ranges, m.angle_min, m.angle_increment, node.now()),
            SENSOR_DATA,
        )
        node.create_subscription(
            Range, topics.ULTRASONIC, lambda m: cache.sonar(m.range, node.now()), SENSOR_DATA
        )
        node.create_subscription(TFMessage, topics.TF_STATIC, cache.tf_static, QoS(depth=20))
        if params.docking_controller.info.infrared:
            node.create_subscription(
                DockInfraRed, topics.IR_DOCK, lambda m: cache.infrared(m, node.now()), SENSOR_DATA
            )
        self.sightings = DockSightings(node, cache.track, self._say, self._event)
        self.dock_server = ActionServer(
            node,
            DOCK_ROBOT,
            topics.DOCK_ROBOT,
            on_goal=_check_dock_goal,
            on_accepted=self._on_dock_goal,
            on_cancel=lambda handle: self._event(CancelGoal(Goal(handle, TaskKind.DOCK))),
            preempt_result=lambda: DockRobotResult(success=False),
        )
        self.undock_server = ActionServer(
            node,
            UNDOCK_ROBOT,
            topics.UNDOCK_ROBOT,
            on_goal=_check_undock_goal,
            on_accepted=self._on_undock_goal,
            on_cancel=lambda handle: self._event(CancelGoal(Goal(handle, TaskKind.UNDOCK))),
            preempt_result=lambda: UndockRobotResult(success=False),
        )
        self.period_s = params.docking_controller.info.control_period_s
        self.timer = node.create_timer(self.period_s, self._on_tick)
        self._log.info(
            "controller %s at %g Hz, %d dock(s) from %s, detection %s, patrol of %d waypoint(s), on %s time%s",
            params.controller,
            1.0 / self.period_s,
            len(database),
            params.dock_database,
            "on" if params.use_detection else "off",
            len(self.executive.patrol),
            "sim" if node.use_sim_time else "wall",
            f", docks reserved with {self.fleet.reserve_key}" if params.fleet else "",
        )

    # --- in --------------------------------------------------------------------------------------------

    def _on_battery(self, msg: BatteryState) -> None:
        now = self.node.now()
        self.inputs.battery(msg, now)
        self._carry_out(
            self.executive.battery_reading(msg.percentage, msg.power_supply_status in CHARGING_STATUSES), now
        )
        if self.executive.decision_due:
            self._on_tick()

    def _heard(self, now_s: float, *, tick: bool = False, clock_reset: bool = False) -> Heard:
        busy = not self.nav.is_task_complete()
        outcome = None if busy else _NAV_OUTCOMES.get(self.nav.get_result(), NavOutcome.FAILED)
        nav = NavHeard(busy, outcome, self.nav.failure_reason() if outcome else "")
        watch = self.peers if tick else None
        peers = tuple(watch.fresh(now_s)) if watch is not None else ()
        own_plan = watch.own_plan(now_s) if watch is not None else None
        return self.inputs.heard(now_s, nav, peers, own_plan, clock_reset)

    def _event(self, event: Event) -> None:
        now = self.node.now()
        self._carry_out(self.executive.handle(event, self._heard(now)), now)

    def _on_tick(self) -> None:
        """The control tick; also run as soon as a planner goal ends, so that the approach taking over from
        navigation starts as the planner lets go (its last command was a stop), not up to a period later,
        and as soon as the mission has a docking to start (:attr:`Executive.decision_due`)."""
        now = self.node.now()
        reset = clock_went_back(now, self._last_now_s)
        if reset:
            self.inputs.forget_poses()
        self._last_now_s = now
        self._carry_out(self.executive.step(self._heard(now, tick=True, clock_reset=reset)), now)

    # --- actions ---------------------------------------------------------------------------------------

    def _on_dock_goal(self, handle: GoalHandle) -> None:
        if not handle.active:
            return
        goal: DockRobotGoal = handle.goal
        handle.execute()
        self._log.info(
            "dock_robot: %s",
            f"dock {goal.dock_id!r}"
            if goal.use_dock_id and goal.dock_id
            else "the nearest dock"
            if goal.use_dock_id
            else "a given pose",
        )
        self._event(
            DockGoal(
                Goal(handle, TaskKind.DOCK),
                DockRequest(
                    dock_id=goal.dock_id if goal.use_dock_id else "",
                    dock_pose=None if goal.use_dock_id else goal.dock_pose.pose.to_pose2d(),
                    dock_type=goal.dock_type,
                    navigate_to_staging_pose=goal.navigate_to_staging_pose,
                    max_staging_time_s=goal.max_staging_time,
                ),
            )
        )

    def _on_undock_goal(self, handle: GoalHandle) -> None:
        if not handle.active:
            return
        handle.execute()
        self._log.info("undock_robot")
        self._event(
            UndockGoal(Goal(handle, TaskKind.UNDOCK), handle.goal.max_undocking_time, handle.goal.dock_type)
        )

    # --- out -------------------------------------------------------------------------------------------

    def _hold(self, tick_s: float, hold: Hold) -> None:
        """Hold the world through a handoff from ``tick_s`` on, or let go (see the drive arbiter)."""
        self.pacing_hold.publish(
            PacingHold(
                Header.at(tick_s, ""),
                holder="docking",
                hold=hold is not Hold.LET_GO,
                until_driven=hold is Hold.UNTIL_DRIVEN,
            )
        )

    def _carry_out(self, effects: Effects, now_s: float) -> None:
        """Do what the executive decided at ``now_s`` (a command says it answers that tick)."""
        answers_s = now_s if self.node.use_sim_time else None
        for effect in effects:
            match effect:
                case Drive(orders):
                    if orders.hold not in (None, Hold.LET_GO) and answers_s is not None:
                        self._hold(answers_s, orders.hold)
                    if orders.cancel_nav:
                        self.nav.cancel_task()
                    if orders.publish is not None:
                        if not self.nav.is_task_complete():
                            # The arbiter never allows this; a stop is still better than nothing if it happens.
                            self._say.error("overlap", "publishing cmd_vel while the planner holds a goal")
                        self.cmd_vel.publish(
                            Twist.planar(orders.publish.linear_x_mps, orders.publish.angular_z_radps),
                            answers_s=answers_s,
                        )
                    if orders.hold is Hold.LET_GO and answers_s is not None:
                        self._hold(answers_s, orders.hold)
                    if orders.send_goal is not None:
                        self.nav.go_to_pose(orders.send_goal, on_done=self._on_tick)
                case WantDetections(wanted):
                    self.sightings.want(wanted)
                case Reserve(battery, dock_id, lengths):
                    self.fleet.reserve(
                        battery,
                        dock_id,
                        lengths,
                        on_answer=lambda answer, error: self._event(FleetReserved(answer, error)),
                    )
                case Release():
                    self.fleet.release(
                        on_done=lambda dock_id, error: self._event(FleetReleased(dock_id, error))
                    )
                case GoalFeedback(goal, feedback):
                    handle: GoalHandle = goal.handle  # type: ignore[assignment]
                    if handle.active:
                        handle.publish_feedback(feedback)
                case GoalEnded(goal, outcome, result):
                    self._answer(goal, outcome, result)
                case PublishState(name):
                    self.state_pub.publish(String(name))
                case Log(level, fmt, args, key):
                    if key is None:
                        self._log.log(level, fmt, *args)
                    else:
                        self._say.log(level, key, fmt, *args)

    def _answer(self, goal: Goal, outcome: Outcome, result: Any) -> None:
        handle: GoalHandle = goal.handle  # type: ignore[assignment]
        if not handle.active:
            return
        if outcome is Outcome.SUCCEEDED:
            handle.succeed(result)
        elif outcome is Outcome.CANCELED:
            handle.canceled(result)
        else:
            handle.abort(result)

    def on_parameter_set(self, name: str, value: object) -> None:
        """``auto_dock`` applies at once (``zendock param set docking auto_dock false``); the other
        runtime-settable parameters are read when a run is built."""
        if name == "auto_dock":
            self.executive.mission.set_auto_dock(bool(value))
            self._log.info("auto_dock %s", "on" if value else "off: the battery trigger starts no docking")

    def close(self) -> None:
        self.timer.cancel()
        if self.executive.task is not None:
            self.executive.task.cancel()
        if not self.nav.is_task_complete():
            self.nav.cancel_task()
        if self.executive.arbiter.moving:
            self.cmd_vel.publish(Twist.planar(0.0, 0.0))
        self.dock_server.close()
        self.undock_server.close()


def _check_dock_goal(goal: DockRobotGoal) -> None:
    if not goal.use_dock_id and goal.dock_pose.header.frame_id not in ("", topics.MAP_FRAME):
        raise ValueError(
            f"dock_pose must be in the {topics.MAP_FRAME} frame, got {goal.dock_pose.header.frame_id!r}"
        )
    if not goal.max_staging_time > 0.0:
        raise ValueError(f"max_staging_time must be > 0, got {goal.max_staging_time}")


def _check_undock_goal(goal: UndockRobotGoal) -> None:
    if not goal.max_undocking_time > 0.0:
        raise ValueError(f"max_undocking_time must be > 0, got {goal.max_undocking_time}")


SERVICE = ServiceSpec(
    "docking",
    Params,
    DockingService,
    description="zendock docking: goes home to charge when the battery runs low; dock_robot and undock_robot",
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
