"""A kinematic world for stepping docking-service tasks without a bus: robot, dock, planner, charger.

The robot is :class:`~services.docking.kinematics.DiffDriveModel`; the localiser is off by ``error`` (in
base_link: the robot believes it is at ``true * error``); the planner reaches each goal after
``nav_duration_s`` (in its believed frame, so the robot really stands at ``goal * error^-1``), or fails;
the plate stops the robot at the dock pose; the charger reports charging while the contacts are mated
(the simulator's tolerances). Intents go through the real :class:`DriveArbiter`, and the world checks
its rule: nothing is published on cmd_vel while the planner holds a goal.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from services.docking.approach import dock_frame_error
from services.docking.drive_arbiter import DriveArbiter, DriveOrders
from services.docking.kinematics import DiffDriveModel
from services.docking.task_io import Navigate, NavOutcome, NavStatus, Task, TickInputs, Velocity
from shared.geometry import Pose2D

SEED_DOCK = Pose2D(-1.0, 0.83, -math.pi / 2)
NO_ERROR = Pose2D()


@dataclass
class WorldLog:
    published: list[tuple[float, Velocity]] = field(default_factory=list)
    goals: list[tuple[float, Pose2D]] = field(default_factory=list)
    cancels: list[float] = field(default_factory=list)
    overlaps: int = 0  # cmd_vel published while the planner held a goal


class KinematicWorld:
    def __init__(
        self,
        start: Pose2D,
        dock: Pose2D = SEED_DOCK,
        error: Pose2D = NO_ERROR,
        period_s: float = 0.05,
        nav_duration_s: float = 1.0,
        nav_fails: int = 0,
        detections: bool = True,
        charger_works: bool = True,
    ) -> None:
        self.robot = DiffDriveModel(start)
        self.dock = dock
        self.error = error
        self.period_s = period_s
        self.nav_duration_s = nav_duration_s
        self.nav_fails = nav_fails
        self.detections = detections
        self.charger_works = charger_works
        self.now_s = 0.0
        self.arbiter = DriveArbiter()
        self.log = WorldLog()
        self.command = Velocity(0.0, 0.0)
        self.blocked_ahead: Callable[[KinematicWorld], bool] = lambda _w: False
        self.blocked_behind: Callable[[KinematicWorld], bool] = lambda _w: False
        self.pose_available: Callable[[KinematicWorld], bool] = lambda _w: True
        self.charging_override: bool | None = None
        self._nav_goal: Pose2D | None = None
        self._nav_done_s = math.inf
        self._nav_outcome: NavOutcome | None = None
        self._next_detection_s = 0.0

    # --- what the robot senses ---------------------------------------------------------------------

    @property
    def true_pose(self) -> Pose2D:
        return self.robot.pose

    @property
    def believed_pose(self) -> Pose2D:
        return self.true_pose.compose(self.error)

    @property
    def mated(self) -> bool:
        e = dock_frame_error(self.true_pose, self.dock)
        return -0.05 <= e.along_m <= 0.01 and abs(e.lateral_m) <= 0.04 and abs(e.yaw_rad) <= 0.1

    @property
    def nav_busy(self) -> bool:
        return self._nav_goal is not None

    def inputs(self) -> TickInputs:
        charging = (
            self.mated and self.charger_works if self.charging_override is None else self.charging_override
        )
        return TickInputs(
            now_s=self.now_s,
            robot_pose=self.believed_pose if self.pose_available(self) else None,
            pose_age_s=0.0,
            base_twist=(self.robot.v_mps, self.robot.w_radps),
            charging=charging,
            nav=NavStatus(self.arbiter.nav_key, self.nav_busy, self._nav_outcome, ""),
            blocked_ahead=self.blocked_ahead(self),
            blocked_behind=self.blocked_behind(self),
        )

    # --- stepping ----------------------------------------------------------------------------------

    def tick(self, task: Task) -> None:  # type: ignore[type-arg]
        self._feed_detections(task)
        inputs = self.inputs()
        intent = task.step(inputs)
        if isinstance(intent, Velocity):
            self._apply(self.arbiter.velocity(intent, self.nav_busy, self.now_s))
        elif isinstance(intent, Navigate):
            self._apply(self.arbiter.navigate(intent))
        if task.done:
            self._apply(self.arbiter.release())
        self._advance(self.period_s)

    def _apply(self, orders: DriveOrders) -> None:
        if orders.cancel_nav and self.nav_busy:
            self.log.cancels.append(self.now_s)
            self._nav_goal, self._nav_outcome = None, NavOutcome.CANCELED
        if orders.publish is not None:
            if self.nav_busy:
                self.log.overlaps += 1
            self.log.published.append((self.now_s, orders.publish))
            self.command = orders.publish
        if orders.send_goal is not None:
            self.log.goals.append((self.now_s, orders.send_goal))
            self._nav_goal, self._nav_outcome = orders.send_goal, None
            self._nav_done_s = self.now_s + self.nav_duration_s
            self.command = Velocity(0.0, 0.0)  # the planner drives now (and stands still at the end)

    def _advance(self, dt_s: float) -> None:
        steps = 10
        for _ in range(steps):
            self.robot.step(self.command.linear_x_mps, self.command.angular_z_radps, dt_s / steps)
            self._plate_stops_robot()
        self.now_s += dt_s
        if self._nav_goal is not None and self.now_s >= self._nav_done_s:
            if self.nav_fails > 0:
                self.nav_fails -= 1
                self._nav_outcome = NavOutcome.FAILED
            else:
                placed = self._nav_goal.compose(self.error.inverse())
                self.robot = DiffDriveModel(placed, self.robot.limits)
                self._nav_outcome = NavOutcome.SUCCEEDED
            self._nav_goal = None

    def _plate_stops_robot(self) -> None:
        e = dock_frame_error(self.true_pose, self.dock)
        if e.along_m > 0.0 and abs(e.lateral_m) < 0.35 and abs(e.yaw_rad) < math.pi / 2:
            back = self.dock.compose(Pose2D(0.0, e.lateral_m, e.yaw_rad))
            self.robot.x, self.robot.y = back.x, back.y
            self.robot.v_mps = 0.0

    def _feed_detections(self, task: Task) -> None:  # type: ignore[type-arg]
        add = getattr(task, "add_detection", None)
        if not self.detections or add is None or self.now_s < self._next_detection_s:
            return
        self._next_detection_s = self.now_s + 1.0 / 15.0
        dock_in_base = self.dock.relative_to(self.true_pose)
        bearing = math.atan2(dock_in_base.y, dock_in_base.x)
        if dock_in_base.x > 0.0 and abs(bearing) < 0.6 and math.hypot(dock_in_base.x, dock_in_base.y) < 2.5:
            add(dock_in_base, self.believed_pose, self.now_s)

    def run(self, task: Task, max_time_s: float, until: Callable[[], bool] | None = None) -> None:  # type: ignore[type-arg]
        end = self.now_s + max_time_s
        while self.now_s < end and not task.done and not (until is not None and until()):
            self.tick(task)
