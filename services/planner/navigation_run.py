"""One navigation goal's life, as a pure state machine: a snapshot in, orders out.

PLANNING (held still until the first path) -> FOLLOWING (regulated pure pursuit; replan every
``replan_period_s``, and at once when the costmap blocks the path or the follower sees a collision
ahead) -> SUCCEEDED inside the goal tolerances, once stopped. A collision ahead that lasts
``blocked_timeout_s`` (or as long in all, on and off, within ``blocked_window_s`` and
``blocked_radius_m``: a robot stopped again and again at the same obstacle), no progress for
``progress_timeout_s``, or a failed plan starts a recovery:
BACKING_UP (only over free cells), then CLEARING (the lidar layer is cleared; every second recovery also
forgets glass round the robot, or all glass once planning has failed past the fourth; the layers refill
for ``recovery_wait_s``), then PLANNING again. A failed plan first asks once for a way through
suspected glass and plans again at once (suspicion alone may close every way: see
:mod:`services.planner.suspicion_way`); so does the plan that ends a recovery a failed plan began. After
``max_recoveries`` the goal is ABORTED with the error code of the last failure. These timeouts run on
the control loop's own clock (sim time, each tick counting at most four periods), so a machine too busy
to run the loop on time does not make the robot look stuck. A stale pose holds the robot still (a map
pose carried forward by fresh odometry is stale only after ``carried_pose_timeout_s``); NO_POSE after
``no_pose_timeout_s``.

The run reads nothing from the bus and writes nothing to it: the planner's node gives it a
:class:`NavSnapshot` (the pose, the measured twist, the cost grid, the clocks) and carries out the
:class:`NavOrders` it returns (publish a command, submit a plan, publish a path, clear the layers, send
feedback, end the action), so the goal's life is unit-tested without a bus, as docking's runs are.
"""

from __future__ import annotations

import enum
import logging
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from services.planner.behaviors import DriveStraight, Outcome, Spin
from services.planner.costmap import LETHAL_OBSTACLE, CostGrid
from services.planner.params import Params
from services.planner.plan_monitor import ActivePlan, ProgressChecker
from services.planner.planning_worker import PlanOutcome
from services.planner.pure_pursuit import FollowStatus, RegulatedPurePursuit
from services.planner.recovery import GlassClearing, glass_clearing
from shared import topics
from shared.frames import clock_went_back
from shared.geometry import Pose2D
from shared.interfaces.navigation import NavigateErrorCode

log = logging.getLogger(__name__)

#: The path ahead this close to the robot is the follower's business, not a reason to replan.
BLOCKED_CHECK_SKIP_M = 0.15
#: No periodic replanning this close to the goal (a new path would reset the follower's goal latch).
NO_REPLAN_WITHIN_M = 0.3
#: Feedback's time estimate uses the measured speed above this, else the speed limit.
ETA_MIN_SPEED_MPS = 0.05

#: Failures to find a path, as against failures to follow one.
PLANNING_FAILURES = frozenset(
    {NavigateErrorCode.NO_VALID_PATH, NavigateErrorCode.START_OCCUPIED, NavigateErrorCode.GOAL_OCCUPIED}
)


class Phase(enum.Enum):
    PLANNING = "planning"
    FOLLOWING = "following"
    BACKING_UP = "backing_up"
    CLEARING = "clearing"
    LOOKING = "looking"


class Ending(enum.Enum):
    SUCCEEDED = "succeeded"
    CANCELED = "canceled"
    ABORTED = "aborted"


@dataclass(frozen=True, slots=True)
class NavSnapshot:
    """What the run sees at one instant."""

    #: The node's clock (sim time).
    now_s: float
    #: A monotonic wall clock: a pose pipeline lagging under load is judged on it too.
    wall_s: float
    #: The robot's pose now (localisation carried by odometry), or None before any.
    pose: Pose2D | None
    #: Time since the last localisation sample arrived.
    pose_age_s: float
    #: Whether fresh odometry carries that sample forward.
    pose_carried: bool
    #: The measured ``(linear, angular)`` twist, or None when odometry is stale.
    velocity: tuple[float, float] | None
    #: The inflated cost grid, or None before a map.
    grid: CostGrid | None
    #: Whether a plan request (this goal's or an earlier one's) is still on the worker.
    planning_in_flight: bool
    #: The last command published on cmd_vel (by any goal).
    last_cmd: tuple[float, float] = (0.0, 0.0)
    #: A cap on the forward speed (near suspected glass), or None.
    speed_limit_mps: float | None = None


@dataclass(frozen=True, slots=True)
class NavEnd:
    """How the goal ended: the action's outcome and result."""

    ending: Ending
    code: NavigateErrorCode
    message: str = ""


@dataclass(frozen=True, slots=True)
class NavFeedback:
    pose: Pose2D
    navigation_time_s: float
    estimated_time_remaining_s: float
    number_of_recoveries: int
    distance_remaining_m: float


@dataclass(slots=True)
class NavOrders:
    """What the node is to do, in this order: publish, open a way, put glass back, plan, clear, feed back, end."""

    #: ``(linear, angular)`` to publish on cmd_vel.
    cmd: tuple[float, float] | None = None
    #: The tick :attr:`cmd` answers, when not the snapshot's: a stop while the first plan is being made
    #: answers the tick that asked for it, so the simulator's lockstep waits for the plan.
    cmd_answers_s: float | None = None
    #: Before the plan request: if suspected glass alone closes every way from this pose to the goal, lift
    #: the outer half of its radius along one way (:mod:`services.planner.suspicion_way`).
    open_way_from: Pose2D | None = None
    #: Submit a plan request from this pose (with the snapshot's grid and :attr:`NavigationRun.generation`).
    plan_from: Pose2D | None = None
    #: A new path to publish on ``plan`` (``(N, 3)`` poses).
    path: np.ndarray | None = None
    #: Clear the sensor layers, and as much glass as this says, around :attr:`clear_around`.
    clear: GlassClearing | None = None
    clear_around: Pose2D | None = None
    #: Before the plan request: the look round after a clearing stopped early, so the glass the clearing
    #: forgot and the sonar has not heard since comes back (a pane's end is not floor for want of a look).
    restore_unheard_glass: bool = False
    feedback: NavFeedback | None = None
    end: NavEnd | None = None


def with_lethal_of(grid: CostGrid, before: CostGrid | None) -> CostGrid:
    """``grid`` with every cell lethal in ``before`` lethal too (the same frame; otherwise ``grid``).

    A recovery's look round turns in place right after the clearing forgot glass: checked against the
    cleared grid alone, the turn put a corner on a pane the robot stood beside, after each such recovery
    (measurement 116). What was lethal a moment ago still stops the turn; what the turn hears is added.
    """
    if before is None or before.frame != grid.frame or before.costs.shape != grid.costs.shape:
        return grid
    lethal_before = before.costs == LETHAL_OBSTACLE
    return CostGrid(grid.frame, np.where(lethal_before, np.uint8(LETHAL_OBSTACLE), grid.costs))


class NavigationRun:
    """One goal, from acceptance to its end; see the module docstring."""

    def __init__(
        self, goal: Pose2D, params: Params, now_s: float, next_generation: Callable[[], int]
    ) -> None:
        self.goal = goal
        self.params = params
        #: Numbers attempts uniquely across goals (a goal's stale plan must not reach the next goal).
        self._next_generation = next_generation
        #: Identifies the plan requests of the current attempt; outcomes of others are stale.
        self.generation = next_generation()
        self.started_s = now_s
        self.phase = Phase.PLANNING
        self.plan: ActivePlan | None = None
        self.recoveries = 0
        #: The current recovery began because no path was found (not because following failed).
        self.recovering_from_planning = False
        #: A failed plan has already asked for a way through suspected glass since the last path found.
        self._opened_way_since_last_plan = False
        self.ended: NavEnd | None = None
        self.follower = RegulatedPurePursuit(params.follower_params())
        self._backup: DriveStraight = params.recovery_backup()
        #: After a recovery that forgot glass the sonar had heard: a turn in place, so the sonar hears
        #: again what is still there before the planner plans through it.
        self._look: Spin | None = None
        #: The grid as it was before that clearing: the turn keeps its corners off what it forgot.
        self._look_guard: CostGrid | None = None
        self._progress = ProgressChecker(
            params.required_movement_m, params.required_rotation_rad, params.progress_timeout_s
        )
        self._last_plan_request_s = -math.inf
        self._replan_wanted = False
        self._blocked_since_s: float | None = None
        #: ``(control time, seconds, x, y)`` of each control tick the follower stopped for a collision ahead,
        #: over the last ``blocked_window_s``: the time blocked on and off at one place adds up.
        self._blocked_ticks: deque[tuple[float, float, float, float]] = deque()
        self._pose_lost_since_s: float | None = None
        self._pose_lost_since_wall_s = 0.0
        self._wait_until_s = 0.0
        self._last_feedback_s = -math.inf
        self._last_tick_s: float | None = None
        #: Control time: sim time as the control loop lived it, each tick counting at most four periods.
        #: The stuck, blocked and recovery timeouts run on it, so a machine too busy to run the loop on
        #: time stretches them instead of blaming the robot.
        self.clock_s = 0.0

    @property
    def active(self) -> bool:
        return self.ended is None

    # --- events -------------------------------------------------------------------------------------

    def start(self, snap: NavSnapshot) -> NavOrders:
        """The goal was accepted: ask for the first plan."""
        orders = NavOrders()
        self._request_plan(snap, orders)
        return orders

    def cancel(self) -> NavOrders:
        orders = NavOrders()
        self._end(orders, Ending.CANCELED, NavigateErrorCode.CANCELED, "canceled on request")
        return orders

    def abort(self, code: NavigateErrorCode, message: str) -> NavOrders:
        orders = NavOrders()
        self._end(orders, Ending.ABORTED, code, message)
        return orders

    def plan_outcome(self, outcome: PlanOutcome, snap: NavSnapshot) -> NavOrders:
        """A plan came back from the worker (``planning_in_flight`` already counts it as back)."""
        orders = NavOrders()
        if not self.active or outcome.request.generation != self.generation:
            return orders
        if self.phase not in (Phase.PLANNING, Phase.FOLLOWING):
            return orders
        if outcome.path is None:
            code = {
                "goal": NavigateErrorCode.GOAL_OCCUPIED,
                "start": NavigateErrorCode.START_OCCUPIED,
            }.get(outcome.blocked_end, NavigateErrorCode.NO_VALID_PATH)
            log.warning("planning failed: %s", outcome.error)
            if snap.pose is None:
                self._replan_wanted = True
                return orders
            if not self._opened_way_since_last_plan:
                # Suspected glass may be all that closes the way: lift part of it along one way and plan
                # again at once; a recovery follows if that finds no path either.
                self._opened_way_since_last_plan = True
                orders.open_way_from = snap.pose
                self._request_plan(snap, orders)
                if orders.plan_from is not None:
                    return orders
            self._start_recovery(snap.pose, code, outcome.error, orders)
            return orders
        self._opened_way_since_last_plan = False
        path = outcome.path
        self.plan = ActivePlan.from_poses(path.poses, outcome.request.grid, snap.now_s)
        self.follower.set_path(path.poses)
        orders.path = path.poses
        log.debug("plan: %.2f m in %.1f ms", path.length_m, 1000.0 * path.planning_time_s)
        if self.phase is Phase.PLANNING:
            self.phase = Phase.FOLLOWING
            self._blocked_since_s = None
            self._progress.reset()
            log.info(
                "following a %.2f m path (planned in %.0f ms)", path.length_m, 1000.0 * path.planning_time_s
            )
        return orders

    def replan(self, snap: NavSnapshot) -> NavOrders:
        """Plan again now (a new map), or as soon as the request in flight is back."""
        orders = NavOrders()
        if self.active:
            self._request_plan(snap, orders, urgent=True)
        return orders

    def costmap_updated(self, snap: NavSnapshot) -> NavOrders:
        """Replan at once when the updated costmap blocks the path ahead."""
        orders = NavOrders()
        if (
            self.active
            and snap.grid is not None
            and self.phase is Phase.FOLLOWING
            and self.plan is not None
            and not self.follower.xy_goal_reached
            and self.plan.newly_blocked(snap.grid, self.follower.closest_index, BLOCKED_CHECK_SKIP_M)
        ):
            log.info("an obstacle blocks the path: replanning")
            self._request_plan(snap, orders, urgent=True)
        return orders

    def tick(self, snap: NavSnapshot) -> NavOrders:
        """One control period."""
        orders = NavOrders()
        if not self.active:
            return orders
        p = self.params
        now = snap.now_s
        if clock_went_back(now, self._last_tick_s):
            log.warning("clock jumped back to %.2f s (a simulator reset?): restarting the goal's timers", now)
            self._restart_timers(now)
        period = 1.0 / p.controller_rate_hz
        dt = period if self._last_tick_s is None else min(max(now - self._last_tick_s, period), 4.0 * period)
        self._last_tick_s = now
        self.clock_s += dt
        if p.navigation_timeout_s > 0 and now - self.started_s > p.navigation_timeout_s:
            self._end(
                orders,
                Ending.ABORTED,
                NavigateErrorCode.TIMEOUT,
                f"goal not reached within navigation_timeout_s={p.navigation_timeout_s:g} s",
            )
            return orders
        pose = self._fresh_pose(snap, orders)
        if pose is None or snap.grid is None:
            return orders
        if self.phase is Phase.FOLLOWING and self.plan is not None:
            self._follow(snap, pose, dt, orders)
        elif self.phase in (Phase.BACKING_UP, Phase.CLEARING, Phase.LOOKING):
            self._recover(snap, pose, orders)
        else:
            orders.cmd = (0.0, 0.0)  # no path yet: hold still
            if self.phase is Phase.PLANNING and (snap.planning_in_flight or orders.plan_from is not None):
                orders.cmd_answers_s = self._last_plan_request_s
        if self.active:
            in_flight = snap.planning_in_flight or orders.plan_from is not None
            if self._replan_wanted and not in_flight and self.phase in (Phase.PLANNING, Phase.FOLLOWING):
                self._request_plan(snap, orders, urgent=True)
            self._feedback(snap, pose, orders)
        return orders

    # --- the parts ----------------------------------------------------------------------------------

    def _end(self, orders: NavOrders, ending: Ending, code: NavigateErrorCode, message: str) -> None:
        """End the goal: one zero command, then silence on cmd_vel."""
        orders.cmd = (0.0, 0.0)
        orders.end = self.ended = NavEnd(ending, code, message)
        self.follower.reset()
        if ending is Ending.ABORTED:
            log.warning("goal aborted (%s): %s", code.name, message)

    def _restart_timers(self, now: float) -> None:
        """After the clock jumped back: every deadline of the goal counts from ``now``."""
        self.started_s = now
        self._last_plan_request_s = -math.inf
        self._blocked_since_s = None
        self._pose_lost_since_s = None
        self._last_feedback_s = -math.inf
        self._last_tick_s = None
        self._progress.reset()

    def _request_plan(self, snap: NavSnapshot, orders: NavOrders, urgent: bool = False) -> None:
        """Plan from the current pose, or remember to once the request in flight is back."""
        in_flight = snap.planning_in_flight or orders.plan_from is not None
        if in_flight or (
            urgent and snap.now_s - self._last_plan_request_s < self.params.min_replan_interval_s
        ):
            self._replan_wanted = True
            return
        if snap.pose is None or snap.grid is None:
            self._replan_wanted = True
            return
        self._replan_wanted = False
        self._last_plan_request_s = snap.now_s
        orders.plan_from = snap.pose

    def _fresh_pose(self, snap: NavSnapshot, orders: NavOrders) -> Pose2D | None:
        """The robot's pose, or ``None`` (robot held, maybe goal aborted) when the pose is stale."""
        p = self.params
        age = snap.pose_age_s
        # map -> odom changes slowly: while fresh odometry carries the pose, a localiser running late
        # (a busy machine) is no reason to stop.
        if age <= p.pose_timeout_s or (age <= p.carried_pose_timeout_s and snap.pose_carried):
            if self._pose_lost_since_s is not None:
                log.info("pose is back: resuming")
            self._pose_lost_since_s = None
            return snap.pose
        if self._pose_lost_since_s is None:
            self._pose_lost_since_s = snap.now_s
            self._pose_lost_since_wall_s = snap.wall_s
            log.warning("no fresh %s (%.2f s old): holding still", topics.POSE2D, age)
        orders.cmd = (0.0, 0.0)
        # Also on the wall clock: at 30x real time a pose pipeline lagging under load is not a lost pose.
        lost_s = min(snap.now_s - self._pose_lost_since_s, snap.wall_s - self._pose_lost_since_wall_s)
        if lost_s > p.no_pose_timeout_s:
            self._end(
                orders,
                Ending.ABORTED,
                NavigateErrorCode.NO_POSE,
                f"no robot pose on {topics.POSE2D} for {p.no_pose_timeout_s:g} s",
            )
        return None

    def _follow(self, snap: NavSnapshot, pose: Pose2D, dt: float, orders: NavOrders) -> None:
        p = self.params
        assert snap.grid is not None and self.plan is not None
        velocity = snap.velocity or snap.last_cmd
        # Acceleration limits (and the lookahead) start from the last command, as Nav2's velocity smoother
        # does in open loop: measured odometry lags the base, and ramping from it would slow every start.
        reference = snap.last_cmd if p.open_loop_acceleration else velocity
        command = self.follower.compute_velocity_command(pose, reference, dt, snap.grid, snap.speed_limit_mps)
        if command.status is FollowStatus.GOAL_REACHED:
            if (
                abs(velocity[0]) > p.trans_stopped_velocity_mps
                or abs(velocity[1]) > p.rot_stopped_velocity_radps
            ):
                # nav2's StoppedGoalChecker: inside the tolerances while still turning is not arrived. Brake
                # and judge again once stopped; an overshoot out of tolerance is then turned back.
                orders.cmd = (0.0, 0.0)
                return
            if not self.follower.confirm_goal(pose):
                log.info("stopped past the goal at (%.3f, %.3f): turning back", pose.x, pose.y)
                orders.cmd = (0.0, 0.0)
                return
            log.info(
                "goal reached at (%.3f, %.3f, %.3f) after %.1f s",
                pose.x,
                pose.y,
                pose.yaw,
                snap.now_s - self.started_s,
            )
            self._end(orders, Ending.SUCCEEDED, NavigateErrorCode.NONE, "")
            return
        if command.status is FollowStatus.COLLISION_AHEAD:
            orders.cmd = (0.0, 0.0)
            if self._blocked_since_s is None:
                self._blocked_since_s = self.clock_s
                log.info(
                    "collision ahead at (%.2f, %.2f, %.2f): stopped, replanning", pose.x, pose.y, pose.yaw
                )
            blocked_here_s = self._blocked_here_s(pose, dt)
            if self.clock_s - self._blocked_since_s > p.blocked_timeout_s:
                self._start_recovery(
                    pose,
                    NavigateErrorCode.STUCK,
                    f"an obstacle blocked the way for {p.blocked_timeout_s:g} s",
                    orders,
                )
            elif blocked_here_s > p.blocked_timeout_s:
                self._start_recovery(
                    pose,
                    NavigateErrorCode.STUCK,
                    f"an obstacle blocked the way for {blocked_here_s:.1f} s on and off within "
                    f"{p.blocked_radius_m:g} m in {p.blocked_window_s:g} s",
                    orders,
                )
            elif not self.follower.xy_goal_reached:
                self._request_plan(snap, orders, urgent=True)
            return
        self._blocked_since_s = None
        orders.cmd = (command.linear_mps, command.angular_radps)
        if not self._progress.check(pose, self.clock_s):
            self._start_recovery(
                pose, NavigateErrorCode.STUCK, f"no progress for {p.progress_timeout_s:g} s", orders
            )
            return
        if (
            snap.now_s - self._last_plan_request_s >= p.replan_period_s
            and not self.follower.xy_goal_reached
            and self.plan.remaining_m(self.follower.closest_index, pose) > NO_REPLAN_WITHIN_M
        ):
            self._request_plan(snap, orders)

    def _blocked_here_s(self, pose: Pose2D, dt: float) -> float:
        """Count this tick as blocked; the seconds blocked within ``blocked_window_s``, near ``pose``."""
        p = self.params
        self._blocked_ticks.append((self.clock_s, dt, pose.x, pose.y))
        while self._blocked_ticks and self._blocked_ticks[0][0] < self.clock_s - p.blocked_window_s:
            self._blocked_ticks.popleft()
        return sum(
            seconds
            for _, seconds, x, y in self._blocked_ticks
            if math.hypot(x - pose.x, y - pose.y) <= p.blocked_radius_m
        )

    def _start_recovery(self, pose: Pose2D, code: NavigateErrorCode, reason: str, orders: NavOrders) -> None:
        p = self.params
        if self.recoveries >= p.max_recoveries:
            self._end(orders, Ending.ABORTED, code, f"{reason} (gave up after {self.recoveries} recoveries)")
            return
        self.recoveries += 1
        self.recovering_from_planning = code in PLANNING_FAILURES
        log.warning(
            "recovery %d of %d (%s): backing up, clearing, replanning",
            self.recoveries,
            p.max_recoveries,
            reason,
        )
        self.generation = self._next_generation()
        self.plan = None
        self._replan_wanted = False
        self._blocked_since_s = None
        self._blocked_ticks.clear()
        self.follower.reset()
        self.phase = Phase.BACKING_UP
        self._backup = self.params.recovery_backup()

    def _recover(self, snap: NavSnapshot, pose: Pose2D, orders: NavOrders) -> None:
        assert snap.grid is not None
        if self.phase is Phase.BACKING_UP:
            step = self._backup.step(pose, self.clock_s, snap.grid)
            if step.outcome is Outcome.RUNNING:
                orders.cmd = step.cmd
                return
            orders.cmd = (0.0, 0.0)
            orders.clear = glass_clearing(self.recoveries, self.recovering_from_planning)
            orders.clear_around = pose
            forgets_heard_glass = orders.clear in (GlassClearing.AROUND_ROBOT, GlassClearing.ALL)
            self._look = self.params.recovery_look_around() if forgets_heard_glass else None
            self._look_guard = snap.grid if forgets_heard_glass else None
            self.phase = Phase.CLEARING
            self._wait_until_s = self.clock_s + self.params.recovery_wait_s
            return
        if self.phase is Phase.LOOKING:
            assert self._look is not None
            step = self._look.step(pose, self.clock_s, with_lethal_of(snap.grid, self._look_guard))
            if step.outcome is Outcome.RUNNING:
                orders.cmd = step.cmd
                return
            if step.outcome is not Outcome.SUCCEEDED:
                log.info("the look round stopped after %.2f rad: %s", step.progress, step.reason)
                orders.restore_unheard_glass = True
            self._look = self._look_guard = None  # looked round (the wait before it is long over): plan
        orders.cmd = (0.0, 0.0)
        if self.clock_s < self._wait_until_s:
            return
        if self._look is not None:
            log.info("looking round before replanning: the recovery forgot glass the sonar had heard")
            self.phase = Phase.LOOKING
            return
        self.phase = Phase.PLANNING
        if self.recovering_from_planning:
            orders.open_way_from = pose
        self._request_plan(snap, orders)

    def _feedback(self, snap: NavSnapshot, pose: Pose2D, orders: NavOrders) -> None:
        if snap.now_s - self._last_feedback_s < 1.0 / self.params.feedback_rate_hz - 1e-6:
            return
        self._last_feedback_s = snap.now_s
        if self.plan is not None:
            remaining = self.plan.remaining_m(self.follower.closest_index, pose)
        else:
            remaining = pose.distance_to(self.goal)
        velocity = snap.velocity or snap.last_cmd
        speed = abs(velocity[0])
        eta = remaining / (speed if speed > ETA_MIN_SPEED_MPS else self.params.max_linear_vel_mps)
        orders.feedback = NavFeedback(
            pose, max(0.0, snap.now_s - self.started_s), eta, self.recoveries, remaining
        )
