"""The goal's life without a bus: a kinematic robot follows the run's commands to the goal, and the run
fails with the right code when it cannot get there."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import numpy as np
import pytest

from services.planner.astar import PlanningError
from services.planner.costmap import LETHAL_OBSTACLE
from services.planner.global_planner import GlobalPlanner
from services.planner.navigation_run import Ending, NavigationRun, NavOrders, NavSnapshot, Phase
from services.planner.params import Params
from services.planner.planning_worker import PlanOutcome, PlanRequest, blocked_end_of
from services.planner.pure_pursuit import FollowStatus, VelocityCommand
from services.planner.recovery import GlassClearing
from shared import structs
from shared.geometry import Pose2D
from shared.interfaces.navigation import NavigateErrorCode
from tests.unit.planner.rooms import room_grid

DT_S = 0.05
AROUND_ROBOT_OR_ALL = {GlassClearing.AROUND_ROBOT, GlassClearing.ALL}


def _grid(walls: list | None = None):  # type: ignore[no-untyped-def]
    return room_grid(5.0, walls, start=(0.6, 1.5, 0.0))


class KinematicWorld:
    """Carries out a run's orders: a unicycle that does what it is told, and a planner that answers at once."""

    def __init__(self, grid, pose: Pose2D, params: Params | None = None) -> None:  # type: ignore[no-untyped-def]
        self.grid = grid
        self.pose = pose
        self.params = params or Params()
        self.planner = GlobalPlanner(self.params.planner_params())
        self.now_s = 0.0
        self.cmd = (0.0, 0.0)
        self.pose_age_s = 0.0
        self.ends: list = []
        self.feedback: list = []
        self.clears: list[GlassClearing] = []
        self.restores: list[bool] = []  # per glass put back: whether a plan was asked for in the same orders
        self.plans = 0
        #: (pose, how many plans had been asked for before it) of each way-through-suspicion order.
        self.open_ways: list[tuple[Pose2D, int]] = []

    def snapshot(self, **overrides: object) -> NavSnapshot:
        values = {
            "now_s": self.now_s,
            "wall_s": self.now_s,
            "pose": self.pose,
            "pose_age_s": self.pose_age_s,
            "pose_carried": True,
            "velocity": self.cmd,
            "grid": self.grid,
            "planning_in_flight": False,
            "last_cmd": self.cmd,
        } | overrides
        return NavSnapshot(**values)  # type: ignore[arg-type]

    def carry_out(self, run: NavigationRun, orders: NavOrders) -> None:
        if orders.cmd is not None:
            self.cmd = orders.cmd
        if orders.clear is not None:
            self.clears.append(orders.clear)
        if orders.restore_unheard_glass:
            self.restores.append(orders.plan_from is not None)  # put back before the plan it is for
        if orders.feedback is not None:
            self.feedback.append(orders.feedback)
        if orders.end is not None:
            self.ends.append(orders.end)
        if orders.open_way_from is not None:
            self.open_ways.append((orders.open_way_from, self.plans))
        if orders.plan_from is not None:
            self.plans += 1
            request = PlanRequest(run.generation, self.grid, orders.plan_from, run.goal)
            try:
                outcome = PlanOutcome(
                    request, self.planner.compute_path(self.grid, orders.plan_from, run.goal)
                )
            except PlanningError as exc:
                outcome = PlanOutcome(request, None, str(exc), blocked_end_of(exc))
            self.carry_out(run, run.plan_outcome(outcome, self.snapshot()))

    def drive(
        self,
        run: NavigationRun,
        until_s: float,
        *,
        until_recovery: bool = False,
        before_tick: Callable[[], None] | None = None,
    ) -> None:
        """Step the robot and the run until ``until_s`` (or the run's end, or its first recovery);
        ``before_tick`` changes the world between the robot's step and the run's tick."""
        while run.active and self.now_s < until_s and not (until_recovery and run.recoveries):
            self.now_s += DT_S
            self.pose = self.pose.advance(self.cmd[0], self.cmd[1], DT_S)
            if before_tick is not None:
                before_tick()
            self.carry_out(run, run.tick(self.snapshot()))


def _run(world: KinematicWorld, goal: Pose2D) -> NavigationRun:
    run = NavigationRun(goal, world.params, world.now_s, itertools.count(1).__next__)
    world.carry_out(run, run.start(world.snapshot()))
    return run


def test_the_robot_follows_the_plan_to_the_goal_and_stops_there() -> None:
    world = KinematicWorld(_grid(), Pose2D(0.6, 1.5, 0.0))
    goal = Pose2D(4.2, 1.0, 0.5)
    run = _run(world, goal)
    assert run.phase is Phase.FOLLOWING  # the first plan came back at once
    world.drive(run, until_s=60.0)
    assert [end.ending for end in world.ends] == [Ending.SUCCEEDED]
    params = world.params
    assert world.pose.distance_to(goal) <= params.xy_goal_tolerance_m + 0.02
    assert world.cmd == (0.0, 0.0) and run.recoveries == 0
    assert world.feedback and world.feedback[-1].distance_remaining_m < world.feedback[0].distance_remaining_m


def test_an_unreachable_goal_recovers_then_aborts_with_the_planning_error() -> None:
    wall = [[[2.5, 0.0], [2.5, 3.0]]]  # splits the room in two
    params = structs.validate(Params, {"max_recoveries": 2, "recovery_wait_s": 0.2}, "params")
    world = KinematicWorld(_grid(wall), Pose2D(0.8, 1.5, 0.0), params)
    run = _run(world, Pose2D(4.0, 1.5, 0.0))
    world.drive(run, until_s=60.0)
    assert len(world.ends) == 1 and world.ends[0].ending is Ending.ABORTED
    assert world.ends[0].code is NavigateErrorCode.NO_VALID_PATH
    assert run.recoveries == 2 and len(world.clears) == 2 and world.cmd == (0.0, 0.0)
    # The first failed plan asks at once for a way through suspected glass and plans again; each recovery
    # a failed plan began asks again just before its own plan.
    assert [plans_before for _, plans_before in world.open_ways] == [1, 2, 3]
    assert world.plans == 4


def test_a_stale_pose_holds_the_robot_then_aborts_with_no_pose() -> None:
    world = KinematicWorld(_grid(), Pose2D(0.6, 1.5, 0.0))
    run = _run(world, Pose2D(4.0, 1.5, 0.0))
    world.drive(run, until_s=1.0)
    world.pose_age_s = 10.0  # the localiser went quiet
    orders = run.tick(world.snapshot(pose_carried=False, now_s=1.05, wall_s=1.05))
    assert orders.cmd == (0.0, 0.0) and orders.end is None
    late = 1.05 + world.params.no_pose_timeout_s + 0.1
    orders = run.tick(world.snapshot(pose_carried=False, now_s=late, wall_s=late))
    assert orders.end is not None and orders.end.code is NavigateErrorCode.NO_POSE


def test_cancel_stops_the_robot_and_a_stale_plan_is_ignored() -> None:
    world = KinematicWorld(_grid(), Pose2D(0.6, 1.5, 0.0))
    run = _run(world, Pose2D(4.0, 1.5, 0.0))
    stale = PlanOutcome(PlanRequest(run.generation - 1, world.grid, world.pose, run.goal), None, "old")
    assert run.plan_outcome(stale, world.snapshot()) == NavOrders()
    orders = run.cancel()
    assert orders.cmd == (0.0, 0.0) and orders.end is not None and orders.end.ending is Ending.CANCELED
    assert run.tick(world.snapshot()) == NavOrders()  # ended: silence on cmd_vel


def test_while_the_first_plan_is_made_its_stops_answer_the_tick_that_asked_for_it() -> None:
    """The simulator's lockstep then waits for the plan instead of running on while the robot stands."""
    world = KinematicWorld(_grid(), Pose2D(0.6, 1.5, 0.0))
    run = NavigationRun(Pose2D(4.2, 1.0, 0.5), world.params, 0.0, itertools.count(1).__next__)
    world.now_s = 1.0
    asked = run.start(world.snapshot())
    assert asked.plan_from is not None  # the plan is asked for at 1.0 s, and not back yet
    for now_s in (1.05, 1.10):
        world.now_s = now_s
        orders = run.tick(world.snapshot(planning_in_flight=True))
        assert orders.cmd == (0.0, 0.0) and orders.cmd_answers_s == 1.0
    # once following, a command answers its own tick (None: the snapshot's)
    world.carry_out(run, run.start(world.snapshot()))
    assert run.phase is Phase.FOLLOWING
    world.now_s = 1.15
    assert run.tick(world.snapshot()).cmd_answers_s is None


def test_a_recovery_that_forgets_heard_glass_turns_once_in_place_before_it_plans_again() -> None:
    """Forgotten glass is planned through at once otherwise: robots drove into panes they had heard."""
    wall = [[[2.5, 0.0], [2.5, 3.0]]]  # no path: every recovery fails, so each kind of clearing comes
    params = structs.validate(Params, {"max_recoveries": 4, "recovery_wait_s": 0.2}, "params")
    world = KinematicWorld(_grid(wall), Pose2D(0.8, 1.5, 0.0), params)
    run = _run(world, Pose2D(4.0, 1.5, 0.0))
    looks: list[float] = []  # rad turned in each look round
    previous = run.phase
    while run.active and world.now_s < 120.0:
        if run.phase is Phase.LOOKING:  # the command the last tick gave is the one the next step carries out
            assert world.cmd[0] == 0.0, "the look round is a turn in place"
            if previous is not Phase.LOOKING:
                looks.append(0.0)
            looks[-1] += abs(world.cmd[1]) * DT_S
        previous = run.phase
        world.drive(run, world.now_s + DT_S)
    assert world.clears == [
        GlassClearing.KEEP,
        GlassClearing.AROUND_ROBOT,
        GlassClearing.KEEP,
        GlassClearing.ALL,
    ]
    assert len(looks) == 2, "one look round for each clearing that forgot heard glass"
    assert world.restores == [], "a look round that turned once round heard again what it could"
    for turned in looks:
        assert abs(turned - 2.0 * math.pi) < 0.15, f"turned {turned:.2f} rad, not once round"
    assert [end.ending for end in world.ends] == [Ending.ABORTED]


def test_a_look_round_keeps_its_corners_off_the_glass_the_clearing_just_forgot() -> None:
    """A recovery forgets the glass round the robot and turns in place to hear it again: beside a pane, a
    turn checked against the cleared grid alone swept a corner into it (a stub by a door, at 0.37 m/s)."""
    split = [[2.5, 0.0], [2.5, 3.0]]  # no path: recoveries follow one another
    beside = [[0.2, 1.71], [1.4, 1.71]]  # a pane along the robot's left side: its corners reach 0.25 m
    heard, forgotten = _grid([split, beside]), _grid([split])
    params = structs.validate(Params, {"max_recoveries": 2, "recovery_wait_s": 0.2}, "params")
    world = KinematicWorld(heard, Pose2D(0.8, 1.5, 0.0), params)
    footprint = (params.robot_length_m, params.robot_width_m)
    run = _run(world, Pose2D(4.0, 1.5, 0.0))
    looked_ticks = 0
    while run.active and world.now_s < 60.0:
        if AROUND_ROBOT_OR_ALL & set(world.clears):
            world.grid = forgotten  # the clearing forgot the pane; it is still there
        if run.phase is Phase.LOOKING:
            looked_ticks += 1
        world.drive(run, world.now_s + DT_S)
        pose = np.array([world.pose.as_tuple()])
        costs = heard.footprint_costs(pose, *footprint)
        assert costs[0] < LETHAL_OBSTACLE, f"a corner met the pane at {world.pose} in {run.phase}"
    assert GlassClearing.AROUND_ROBOT in world.clears and looked_ticks > 0, "no look round was tried"
    assert world.restores and all(world.restores), "the stopped look round's glass goes back before planning"


def _drive_past_flickers(params: Params) -> tuple[KinematicWorld, NavigationRun]:
    """Every 1.5 s a short wall shows up for 0.5 s, 0.45 m ahead of the robot wherever it is (a sensor's
    phantom): each time the follower stops, for less than ``blocked_timeout_s``."""
    clear = _grid()
    world = KinematicWorld(clear, Pose2D(0.6, 1.5, 0.0), params)
    run = _run(world, Pose2D(4.4, 1.5, 0.0))
    shown_at: float | None = None

    def flicker() -> None:
        nonlocal shown_at
        if world.now_s % 1.5 < DT_S and world.now_s > 1.0:
            pose = world.pose
            cx, cy = pose.x + 0.45 * math.cos(pose.yaw), pose.y + 0.45 * math.sin(pose.yaw)
            dx, dy = -0.25 * math.sin(pose.yaw), 0.25 * math.cos(pose.yaw)
            wall = [[[cx - dx, cy - dy], [cx + dx, cy + dy]]]
            world.grid, shown_at = room_grid(5.0, wall, start=(0.6, 1.5, 0.0)), world.now_s
        elif shown_at is not None and world.now_s - shown_at >= 0.5:
            world.grid, shown_at = clear, None

    world.drive(run, 30.0, until_recovery=True, before_tick=flicker)
    return world, run


class _BackAndForth:
    """A follower that drives 0.3 m forward, is stopped by a collision ahead, drives back, is stopped
    again, ...: never blocked for ``blocked_timeout_s`` at a time, always moving in between, going nowhere
    (what the robot did for 150 s beside a glass pane, measurement 106)."""

    def __init__(self, follower) -> None:  # type: ignore[no-untyped-def]
        self._follower = follower
        self._ticks = 0

    def __getattr__(self, name: str):  # type: ignore[no-untyped-def]
        return getattr(self._follower, name)

    def compute_velocity_command(self, *args, **kwargs) -> VelocityCommand:  # type: ignore[no-untyped-def]
        self._ticks += 1
        cycle, tick = divmod(self._ticks, 30)
        if tick >= 20:  # 0.5 s stopped, shorter than blocked_timeout_s
            return VelocityCommand(0.0, 0.0, FollowStatus.COLLISION_AHEAD)
        return VelocityCommand(0.3 if cycle % 2 == 0 else -0.3, 0.0, FollowStatus.FOLLOWING)


class _TurningAtTheObstacle(_BackAndForth):
    """A follower turning in place towards its path, stopped by the collision check every other tick."""

    def compute_velocity_command(self, *args, **kwargs) -> VelocityCommand:  # type: ignore[no-untyped-def]
        self._ticks += 1
        if self._ticks % 2:
            return VelocityCommand(0.0, 0.0, FollowStatus.COLLISION_AHEAD)
        return VelocityCommand(0.0, 0.4, FollowStatus.ROTATING_TO_PATH)


def _back_and_forth(params: Params, follower=_BackAndForth) -> tuple[KinematicWorld, NavigationRun]:  # type: ignore[no-untyped-def]
    world = KinematicWorld(_grid(), Pose2D(0.6, 1.5, 0.0), params)
    run = _run(world, Pose2D(4.4, 1.5, 0.0))
    run.follower = follower(run.follower)
    world.drive(run, 60.0, until_recovery=True)
    return world, run


def test_blocked_again_and_again_at_the_same_place_starts_a_recovery() -> None:
    # Never blocked for blocked_timeout_s at a time, and moving in between: 0.5 s blocked each 1.5 s adds up
    # to the 2 s at the end of the fourth stop.
    world, run = _back_and_forth(Params())
    assert run.recoveries == 1 and run.active, f"no recovery after {world.now_s:.1f} s"
    assert world.now_s == pytest.approx(1.5 * 3 + 1.5, abs=0.2)
    assert not run._blocked_ticks  # a recovery starts the sum afresh
    # Counting only how long each stop lasts, nothing ends it: no recovery in a minute.
    world, run = _back_and_forth(structs.validate(Params, {"blocked_window_s": 0.6}, "params"))
    assert run.recoveries == 0 and run.active and world.now_s >= 60.0


def test_stops_spread_along_the_way_are_progress_not_a_reason_to_recover() -> None:
    world, run = _drive_past_flickers(Params())
    assert run.recoveries == 0, f"a recovery after {world.now_s:.1f} s at {world.pose}"
    assert world.pose.x > 3.0  # it got on, stopping every few steps


def test_turning_in_place_blocked_every_other_tick_is_blocked_half_the_time() -> None:
    world, run = _back_and_forth(Params(), follower=_TurningAtTheObstacle)
    assert run.recoveries == 1
    assert world.now_s == pytest.approx(2 * Params().blocked_timeout_s, abs=0.2)
