"""The docking service's executive: which task runs, and what the service does about it.

Pure: no bus, no clock. The node hands it what it hears (:class:`~services.docking.heard.Heard`) and
what happens (:data:`Event`: action goals and cancels, the fleet's answers, dock sightings, battery
readings); it answers with :data:`Effects`, a list of plain data the node carries out in order (drive
orders, fleet requests, action feedback and results, the state to publish). Each control tick
(:meth:`Executive.step`) it

1. follows the mission (:class:`~services.docking.mission.Mission`): patrol, go home when low, resume;
2. with a fleet, follows the dock claim (:class:`~services.docking.dock_claim.DockClaim`): ask, renew and
   release; start docking once a dock is granted, or seen free with the fleet down;
3. with a fleet in the room, follows the traffic rule (:mod:`services.docking.traffic`): a robot met on
   the way may make this one give way, and the interrupted docking carries on afterwards;
4. steps the running task with a :class:`~services.docking.task_io.TickInputs` snapshot and turns its
   intent into drive orders through the :class:`~services.docking.drive_arbiter.DriveArbiter`, so the
   service and the planner never drive at once;
5. reports (:class:`~services.docking.reporting.Reporter`): dock_robot feedback on change (and every
   ``feedback_period_s``), ``docking/state`` on change and every second.

Which task runs, what replacing and ending it answer, and the two tasks the executive starts for reasons of
its own (waiting for a dock, giving way) are the task-life policy's
(:class:`~services.docking.task_life.TaskLife`); the executive acts on how a task ended (resume after a
give-way, tell the mission, let go of the dock claim). Tasks answer one protocol
(:class:`~services.docking.task_io.Task`), so nothing here asks which kind runs. Action goals are opaque
here: :class:`Goal` carries the node's handle and which action it is.
"""

from __future__ import annotations

import logging
from dataclasses import replace

from services.docking.dock_claim import AwaitDock, DockClaim, docks_seen_free
from services.docking.dock_db import DockDatabase
from services.docking.docking_run import DockRequest
from services.docking.drive_arbiter import DriveArbiter, DriveOrders
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
    Log,
    Release,
    Reserve,
    UndockGoal,
    WantDetections,
)
from services.docking.heard import DockSighting, Heard
from services.docking.mission import Mission, MissionMode, MissionOrder, TaskKind
from services.docking.params import Params
from services.docking.patrol import Patrol
from services.docking.reporting import Reporter, result_message
from services.docking.room_paths import RoomPaths
from services.docking.safety import ObstacleParams
from services.docking.task_io import Intent, Navigate, NavStatus, Outcome, Task, TickInputs, Velocity
from services.docking.task_life import TaskLife
from services.docking.traffic_policy import TrafficPolicy
from services.docking.undocking_run import UndockingRun
from shared.fleet_answer import FleetAnswer
from shared.geometry import Pose2D
from shared.interfaces.docking import UndockRobotGoal
from shared.world import World


class Executive:
    """See the module docstring."""

    def __init__(self, params: Params, database: DockDatabase, room: World | None, namespace: str) -> None:
        self.params = params
        self.database = database
        self.namespace = namespace
        #: Whether debug lines are wanted (the hold diagnostics cost a line each tick otherwise).
        self.debug = False
        name = namespace.rpartition("/")[2]
        patrol = params.patrol or (
            next((list(r.patrol) for r in room.robots if r.name == name), [])
            if room is not None and name
            else []
        )
        self.patrol = [Pose2D.from_seq(p) for p in patrol]
        self.mission = Mission(self.patrol, params.resume_at, params.low_battery_threshold, params.auto_dock)
        self.arbiter = DriveArbiter()
        self.obstacles = ObstacleParams(stop_distance_m=params.obstacle_stop_distance_m)
        #: Robots sharing docks ask the fleet for one (the node sends what :class:`Reserve` says).
        self.claim = DockClaim(patience_s=params.fleet_patience_s) if params.fleet else None
        #: The room's walls, for passing places (the traffic rule) and path lengths to the docks.
        self.walls = [*room.opaque_segments(), *room.glass] if params.fleet and room is not None else []
        self._room_paths = RoomPaths(room.bounds, self.walls) if self.walls and room is not None else None
        self.traffic = TrafficPolicy(namespace, self.walls)
        self.reporter = Reporter(params.feedback_period_s)
        self.life = TaskLife(self.mission)
        self._approach = params.approach_controller()
        self._applied_correction: Pose2D | None = None

    @property
    def task(self) -> Task | None:
        """The running task, if any."""
        return self.life.task

    @property
    def watches_traffic(self) -> bool:
        """Whether the traffic rule applies (a fleet in a room with walls): the node then watches the peers."""
        return bool(self.walls)

    # --- what happens ----------------------------------------------------------------------------------

    @property
    def decision_due(self) -> bool:
        """Whether the mission has a docking to start (the battery trigger fired, or auto_dock came on while
        low): the node then ticks at once, so the docking begins on the reading's own time, not up to a
        control period later."""
        return self.mission.dock_wanted

    def battery_reading(self, percentage: float, charging: bool) -> Effects:
        if not self.mission.battery(percentage, charging):
            return []
        threshold = 100.0 * self.params.low_battery_threshold
        if not self.mission.auto_dock:
            return [
                Log.info(
                    "battery at %.1f%%, below %.0f%%: auto_dock is off, not docking",
                    100.0 * percentage,
                    threshold,
                )
            ]
        return [Log.info("battery at %.1f%%, below %.0f%%: going home", 100.0 * percentage, threshold)]

    def handle(self, event: Event, heard: Heard) -> Effects:
        """React to ``event`` at once (an action's goal replaces what runs before the next tick)."""
        out: Effects = []
        match event:
            case DockGoal(goal, request):
                self._begin_docking(request, goal, heard, out)
            case UndockGoal(goal, max_time_s, dock_type):
                self._start(self._undocking_run(max_time_s, dock_type), TaskKind.UNDOCK, goal, out)
            case CancelGoal(goal):
                if goal.same(self.life.goal) and self.task is not None:
                    out.append(Log.info("%s: cancel requested", type(self.task).__name__))
                    self.task.cancel()
                else:
                    out.append(GoalEnded(goal, Outcome.CANCELED, result_message(goal.action, None)))
            case FleetReserved(answer, error):
                self._reserved(answer, error, heard.now_s, out)
            case FleetReleased(dock_id, error):
                self._released(dock_id, error, heard.now_s, out)
            case DockSighting():
                if self.task is not None:
                    self._follow_correction(heard.map_to_odom)
                    self.task.add_detection(event.dock_in_base, event.robot_at_stamp, event.stamp_s)
        return out

    # --- the tick --------------------------------------------------------------------------------------

    def step(self, heard: Heard) -> Effects:
        """One control tick; see the module docstring."""
        out: Effects = []
        now = heard.now_s
        if heard.clock_reset:
            out.append(
                Log.warning(
                    "clock jumped back to %.3f s (a reset?): forgetting the pose history and what runs", now
                )
            )
            self.mission.trigger.reset()  # a low battery after the reset sends the robot home again
            if self.task is not None:
                self.task.cancel()
        self._follow_mission(heard, out)
        if self.claim is not None:
            self._follow_fleet(self.claim, heard, out)
        if self.watches_traffic:
            self._follow_traffic(heard, out)
        task = self.task
        out.append(WantDetections(task is not None and task.wants_detections(heard.latest_pose)))
        if task is not None:
            self._follow_correction(heard.map_to_odom)
            inputs = self._task_inputs(task, heard)
            intent = task.step(inputs)
            self.life.holds(task, out)
            if task.holding and self.debug:
                out.append(
                    Log(
                        logging.DEBUG,
                        "hold t=%.3f %s: localisation %.3f s old, odometry %.3f s old",
                        (now, task.holding, heard.localisation_age_s, heard.odometry_age_s),
                    )
                )
            out.append(Drive(self._orders(intent, inputs)))
            self.reporter.feedback(task, self.life.goal, now, out)
            if task.done:
                self._end_task(heard, out)
        self.reporter.state(self.state_name(heard.charging), now, out)
        return out

    def _task_inputs(self, task: Task, heard: Heard) -> TickInputs:
        blocked_ahead = blocked_behind = False
        robot = heard.robot_pose
        if task.watches_obstacles and (robot is not None or not task.obstacles_need_map_pose):
            dock = task.dock_to_excuse()
            dock_in_base = dock.relative_to(robot) if dock is not None and robot is not None else None
            blocked_ahead, blocked_behind = heard.blocked(
                dock_in_base, self.obstacles, self.params.use_lidar, self.params.use_sonar
            )
        nav = heard.nav
        outcome = nav.outcome if not nav.busy and self.arbiter.nav_key is not None else None
        return TickInputs(
            now_s=heard.now_s,
            robot_pose=heard.robot_pose,
            pose_age_s=heard.pose_age_s,
            base_twist=heard.base_twist,
            charging=heard.charging,
            nav=NavStatus(self.arbiter.nav_key, nav.busy, outcome, nav.reason if outcome else ""),
            blocked_ahead=blocked_ahead,
            blocked_behind=blocked_behind,
            ir_dock=heard.ir_dock,
        )

    def _orders(self, intent: Intent, inputs: TickInputs) -> DriveOrders:
        if isinstance(intent, Velocity):
            return self.arbiter.velocity(intent, inputs.nav.busy, inputs.now_s)
        if isinstance(intent, Navigate):
            return self.arbiter.navigate(intent)
        return DriveOrders()

    def _follow_correction(self, correction: Pose2D | None) -> None:
        """Move the detected dock with every change of the localiser's map -> odom correction, so that it
        stays where odometry put it relative to the robot (see :mod:`services.docking.dock_tracker`)."""
        applied = self._applied_correction
        if self.task is not None and correction is not None and applied is not None and correction != applied:
            self.task.relocalised(correction.compose(applied.inverse()))
        self._applied_correction = correction

    def _follow_mission(self, heard: Heard, out: Effects) -> None:
        order = self.mission.decide(heard.now_s, self.life.kind)
        if order is MissionOrder.DOCK:
            request = DockRequest(
                dock_id=self.params.dock_id, max_staging_time_s=self.params.max_staging_time_s
            )
            self._begin_docking(request, None, heard, out)
        elif order is MissionOrder.UNDOCK:
            out.append(
                Log.info("charged to %.0f%%: undocking to resume the patrol", 100.0 * self.mission.percentage)
            )
            self._start(
                self._undocking_run(UndockRobotGoal().max_undocking_time, ""), TaskKind.UNDOCK, None, out
            )
        elif order is MissionOrder.PATROL:
            out.append(Log.info("patrolling from waypoint %d", self.mission.next_waypoint))
            self._start(Patrol(self.mission.patrol, self.mission.next_waypoint), TaskKind.PATROL, None, out)

    # --- the fleet -------------------------------------------------------------------------------------

    def _begin_docking(self, request: DockRequest, goal: Goal | None, heard: Heard, out: Effects) -> None:
        """Dock now, or (sharing docks) once the fleet grants one: wait in :class:`AwaitDock` till then."""
        claim = self.claim
        if claim is None or request.dock_pose is not None:
            self._start(self._docking_run(request, heard), TaskKind.DOCK, goal, out)
            return
        claim.want(heard.now_s, request.dock_id)
        granted = claim.granted_dock
        if granted is not None:
            self._start(self._docking_run(replace(request, dock_id=granted), heard), TaskKind.DOCK, goal, out)
        else:
            out.append(
                Log.info(
                    "asking the fleet for %s", f"dock {request.dock_id!r}" if request.dock_id else "a dock"
                )
            )
            waiting = AwaitDock(request)
            self._start(waiting, TaskKind.DOCK, goal, out)

    def _follow_fleet(self, claim: DockClaim, heard: Heard, out: Effects) -> None:
        """Ask, renew and release as due; start docking once a dock is granted (or seen free, the fleet down)."""
        now = heard.now_s
        waiting = self.life.awaiting
        if waiting is not None:
            granted = claim.granted_dock
            if granted is not None:
                out.append(Log.info("the fleet granted dock %s", granted))
                self._start(
                    self._docking_run(replace(waiting.request, dock_id=granted), heard),
                    TaskKind.DOCK,
                    self.life.goal,
                    out,
                )
            elif claim.fleet_down(now):
                self._dock_without_fleet(claim, waiting, heard, out)
        elif (
            self.task is None and claim.granted_dock is None and heard.charging and not claim.release_pending
        ):
            # In a dock without a claim (started there, or the fleet lost its book): claim the dock it is in.
            if heard.latest_pose is not None:
                claim.holds(now, self.database.nearest(heard.latest_pose).id)
        if claim.asked_to_leave and self.mission.leave_dock():
            out.append(
                Log.info("the fleet asks this robot to leave its dock for a robot whose battery is critical")
            )
        if claim.reserve_due(now):
            if heard.battery is None or not 0.0 <= heard.battery <= 1.0:
                return  # the fleet serves by charge: ask once the battery has spoken
            lengths = None
            if heard.latest_pose is not None and claim.granted_dock is None:
                lengths = self.dock_distances(heard.latest_pose)
            claim.sent(now)
            out.append(Reserve(heard.battery, claim.dock_id, lengths))
        elif claim.release_due(now):
            claim.sent(now)
            out.append(Release())

    def dock_distances(self, robot: Pose2D) -> dict[str, float]:
        """How far each dock is to drive to (the fleet grants the nearest free one): through the room to its
        staging pose and on into the dock, or (a plain dock database, no room) in a straight line."""
        docks = {d.id: d.pose2d for d in self.database}
        if self._room_paths is None:
            return {dock_id: robot.distance_to(pose) for dock_id, pose in docks.items()}
        staging = [self._approach.staging_pose(pose) for pose in docks.values()]
        found = self._room_paths.lengths(robot, staging)
        return {
            dock_id: length + stage.distance_to(pose)
            for (dock_id, pose), stage, length in zip(docks.items(), staging, found, strict=True)
        }

    def _reserved(
        self, answer: FleetAnswer | None, error: Exception | None, now: float, out: Effects
    ) -> None:
        claim = self.claim
        if claim is None:
            return
        if answer is None:
            claim.unanswered(now)
            out.append(Log.now_and_then(logging.WARNING, "fleet", "the fleet did not answer: %s", error))
            return
        if answer.refused:
            out.append(
                Log.now_and_then(logging.WARNING, "fleet-refused", "the fleet refused: %s", answer.reason)
            )
        claim.answered(now, answer)
        if self.life.awaiting is not None and not answer.granted:
            if answer.queue_position:
                out.append(
                    Log.now_and_then(
                        logging.INFO,
                        "queued",
                        "waiting for a dock: number %d in the queue (%s)",
                        answer.queue_position,
                        answer.reason,
                    )
                )
            self.life.awaiting.hold_at(answer.holding_pose)

    def _released(self, dock_id: str | None, error: Exception | None, now: float, out: Effects) -> None:
        claim = self.claim
        if claim is None:
            return
        if dock_id is None:
            claim.unanswered(now)
            out.append(
                Log.now_and_then(logging.WARNING, "fleet", "the fleet did not answer a release: %s", error)
            )
            return
        claim.released(now)
        if dock_id:
            out.append(Log.info("released dock %s", dock_id))

    def _dock_without_fleet(self, claim: DockClaim, waiting: AwaitDock, heard: Heard, out: Effects) -> None:
        """The fleet is down: dock at the nearest dock seen free (no robot in it), keeping it as a claim so
        the fleet learns of it when it is back."""
        if heard.latest_pose is None:
            return
        wanted = waiting.request.dock_id
        docks = [(d.id, d.pose2d) for d in self.database if not wanted or d.id == wanted]
        free = docks_seen_free(docks, heard.latest_pose, heard.scan_points)
        if not free:
            out.append(
                Log.now_and_then(
                    logging.WARNING, "fleet-down", "the fleet is down and no dock is seen free: waiting"
                )
            )
            return
        out.append(
            Log.warning(
                "the fleet has not answered for %g s: docking at %s, seen free", claim.patience_s, free[0]
            )
        )
        claim.holds(heard.now_s, free[0])
        self._start(
            self._docking_run(replace(waiting.request, dock_id=free[0]), heard),
            TaskKind.DOCK,
            self.life.goal,
            out,
        )

    # --- traffic ---------------------------------------------------------------------------------------

    def _follow_traffic(self, heard: Heard, out: Effects) -> None:
        """Give way to a robot with priority met on the way (the traffic policy decides)."""
        if self.life.giving_way is not None:
            self.traffic.watch(self.life.giving_way, heard)
            return
        task = self.task
        if task is None or not task.under_way:
            return
        giving_way = self.traffic.meet(heard, task.dock_request, out)
        if giving_way is not None:
            assert self.life.kind is not None
            self._start(giving_way, self.life.kind, self.life.goal, out)

    # --- task life -------------------------------------------------------------------------------------

    def _docking_run(self, request: DockRequest, heard: Heard) -> Task:
        p = self.params
        return p.docking_controller.docking_run(p, request, self.database, heard.latest_pose)

    def _undocking_run(self, max_time_s: float, dock_type: str) -> UndockingRun:
        return UndockingRun(self.database, max_time_s, dock_type, self.params.undock_config())

    def _start(self, task: Task, kind: TaskKind, goal: Goal | None, out: Effects) -> None:
        """Run ``task`` from the next tick on, replacing whatever runs (its action, if any, is cancelled)."""
        replaced_waiting = self.life.start(task, kind, goal, out)
        if replaced_waiting is not None and kind is not TaskKind.DOCK and self.claim is not None:
            self.claim.drop()  # no longer waiting for a dock
        self.reporter.new_task()

    def _end_task(self, heard: Heard, out: Effects) -> None:
        out.append(Drive(self.arbiter.release()))
        ended = self.life.end(heard.now_s, out)
        if ended.gave_way is not None and ended.result.success:
            self.traffic.gave_way(ended.gave_way, heard.now_s, out)
            if isinstance(ended.gave_way.resume, DockRequest):
                # carry on docking (a patrol: the mission)
                self._begin_docking(ended.gave_way.resume, ended.goal, heard, out)
            return
        # A give-way cancelled (its dock_robot goal, or a clock reset) ends what it interrupted: the goal is
        # answered as cancelled, not resumed.
        kind, result = ended.kind, ended.result
        self.mission.finished(kind, result.success, ended.goal is not None, heard.now_s)
        if self.claim is not None and (
            (kind is TaskKind.DOCK and not result.success) or (kind is TaskKind.UNDOCK and result.success)
        ):
            self.claim.drop()  # out of the dock (or never got in): the dock is free for others

    # --- reports ---------------------------------------------------------------------------------------

    def state_name(self, charging: bool) -> str:
        """What the service is doing, for ``docking/state``."""
        if self.task is not None:
            return self.task.state_name()
        if charging:
            return "DOCKED"
        return "HOLDING" if self.mission.mode is MissionMode.HOLDING else "IDLE"
