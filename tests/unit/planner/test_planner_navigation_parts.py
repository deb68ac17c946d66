"""The planner node's pure parts: goal checks, plan monitoring, the back-up recovery, messages,
the planning worker, the shortest-path yardstick, sonar/lidar fusion, glass memory and the parameters."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest

from services.planner.astar import AStarParams
from services.planner.costmap import LETHAL_OBSTACLE, CostmapParams, LayeredCostmap
from services.planner.glass_memory import GlassMemory
from services.planner.global_planner import GlobalPlannerParams
from services.planner.goal_check import check_goal_on_grid, goal_pose
from services.planner.map_messages import (
    costmap_message,
    occupancy_grid_message,
    occupancy_map_from_message,
    path_message,
)
from services.planner.occupancy_map import OccupancyMap
from services.planner.params import Params
from services.planner.plan_monitor import ActivePlan, ProgressChecker
from services.planner.planning_worker import PlanningWorker, PlanOutcome, PlanRequest
from services.planner.rasterize import map_from_world
from services.planner.recovery import GlassClearing, glass_clearing
from services.planner.shortest_path import shortest_path_length_m
from services.planner.sonar_fusion import echo_explained_by_lidar
from shared import structs
from shared.config_errors import ConfigError
from shared.geometry import Pose2D
from shared.messages import Header, OccupancyGrid, Path, Point, Pose, PoseStamped, Quaternion
from shared.world import World, load_world, parse_world
from tests.support.processes import REPO_ROOT

SEED_ROOM = REPO_ROOT / "deploy/worlds/seed_room.yaml"
GLASS_ROOM = REPO_ROOT / "deploy/worlds/glass_room.yaml"


def _room(walls: list | None = None) -> World:
    return parse_world(
        {
            "name": "room",
            "bounds": [0.0, 0.0, 4.0, 3.0],
            "walls": walls or [],
            "robot": {"start": [0.5, 1.5, 0.0]},
        }
    )


def _grid(world: World):  # type: ignore[no-untyped-def]
    return LayeredCostmap(map_from_world(world), CostmapParams()).grid()


def _goal(x: float = 1.0, y: float = 2.0, yaw: float = 0.5, frame: str = "map") -> PoseStamped:
    return PoseStamped(Header(frame_id=frame), Pose(Point(x, y, 0.0), Quaternion.from_yaw(yaw)))


# --- goal checks -----------------------------------------------------------------------------------


def test_goal_pose_accepts_the_map_frame_and_normalises_the_quaternion() -> None:
    assert goal_pose(_goal()) == Pose2D(1.0, 2.0, pytest.approx(0.5))
    assert goal_pose(_goal(frame="")).yaw == pytest.approx(0.5)
    assert goal_pose(_goal(frame="/map")).x == 1.0
    scaled = _goal()
    q = scaled.pose.orientation
    scaled.pose.orientation = Quaternion(0.0, 0.0, 3 * q.z, 3 * q.w)
    assert goal_pose(scaled).yaw == pytest.approx(0.5)


@pytest.mark.parametrize(
    ("goal", "reason"),
    [
        (_goal(frame="odom"), "frame_id 'odom'"),
        (
            PoseStamped(Header(frame_id="map"), Pose(Point(0, 0, 0), Quaternion(0, 0, 0, 0))),
            "zero quaternion",
        ),
    ],
)
def test_goal_pose_refusals_say_why(goal: PoseStamped, reason: str) -> None:
    with pytest.raises(ValueError, match=reason):
        goal_pose(goal)


def test_goal_pose_refuses_non_finite_numbers() -> None:
    goal = _goal()
    object.__setattr__(goal.pose.position, "x", math.nan)  # a message built in-process, never encoded
    with pytest.raises(ValueError, match="not finite: position.x=nan"):
        goal_pose(goal)


def test_goals_off_the_map_or_in_walls_are_refused_and_near_walls_accepted() -> None:
    grid = _grid(_room(walls=[[[2.0, 0.0], [2.0, 3.0]]]))
    astar = AStarParams(snap_radius_m=0.3)
    check_goal_on_grid(grid, 1.0, 1.5, astar)
    check_goal_on_grid(grid, 2.0, 1.5, astar)  # on the wall, but a free cell lies within 0.3 m
    with pytest.raises(ValueError, match="outside the map"):
        check_goal_on_grid(grid, 9.0, 1.5, astar)
    with pytest.raises(ValueError, match="lethal space"):
        check_goal_on_grid(grid, 2.0, 1.5, AStarParams(snap_radius_m=0.1))
    with pytest.raises(ValueError, match="unknown space"):
        check_goal_on_grid(grid, -0.4, 1.5, AStarParams(snap_radius_m=0.1))  # the unknown margin
    check_goal_on_grid(grid, -0.4, 1.5, AStarParams(snap_radius_m=0.1, allow_unknown=True))


# --- plan monitoring -------------------------------------------------------------------------------


def _straight_plan(grid, y: float = 1.5) -> ActivePlan:  # type: ignore[no-untyped-def]
    xs = np.linspace(0.5, 3.5, 61)
    poses = np.stack([xs, np.full_like(xs, y), np.zeros_like(xs)], axis=1)
    return ActivePlan.from_poses(poses, grid, planned_at_s=0.0)


def test_remaining_distance_follows_the_path_from_the_closest_pose() -> None:
    plan = _straight_plan(_grid(_room()))
    assert plan.length_m == pytest.approx(3.0)
    assert plan.remaining_m(0, Pose2D(0.5, 1.5, 0.0)) == pytest.approx(3.0)
    assert plan.remaining_m(20, Pose2D(1.5, 1.8, 0.0)) == pytest.approx(2.0 + 0.3)


def test_only_new_obstacles_ahead_block_a_plan() -> None:
    room = _room()
    costmap = LayeredCostmap(map_from_world(room), CostmapParams())
    plan = _straight_plan(costmap.grid())
    assert not plan.newly_blocked(costmap.grid(), 0, skip_m=0.15)
    # A new obstacle across the path 1.5 m ahead of (1.0, 1.5), seen by the lidar.
    costmap.update_with_scan((1.0, 1.5), np.array([[2.5, 1.5 + dy] for dy in np.arange(-0.2, 0.21, 0.05)]))
    assert plan.newly_blocked(costmap.grid(), 0, skip_m=0.15)
    # Once the robot is past it, it no longer counts.
    assert not plan.newly_blocked(costmap.grid(), 50, skip_m=0.15)


def test_a_path_planned_through_inflation_is_not_blocked_by_it() -> None:
    grid = _grid(_room(walls=[[[0.0, 1.6], [4.0, 1.6]]]))  # the path runs 0.1 m from a wall
    plan = _straight_plan(grid)
    assert (plan.planned_costs >= 253).any()
    assert not plan.newly_blocked(grid, 0, skip_m=0.15)


def test_progress_checker_needs_movement_or_rotation_within_the_allowance() -> None:
    checker = ProgressChecker(required_movement_m=0.25, required_rotation_rad=0.5, time_allowance_s=10.0)
    assert checker.check(Pose2D(0, 0, 0), 0.0)
    assert checker.check(Pose2D(0.1, 0, 0), 9.0)
    assert not checker.check(Pose2D(0.2, 0, 0), 10.5)
    checker.reset()
    assert checker.check(Pose2D(0, 0, 0), 20.0)
    assert checker.check(Pose2D(0.0, 0.0, 0.6), 29.0)  # turning counts
    assert checker.check(Pose2D(0.0, 0.0, 0.6), 38.0)
    assert not checker.check(Pose2D(0.0, 0.0, 0.6), 39.5)


# --- messages --------------------------------------------------------------------------------------


def test_occupancy_grid_round_trip_keeps_layout_and_origin() -> None:
    occupancy = map_from_world(load_world(SEED_ROOM))
    msg = occupancy_grid_message(occupancy, 12.5, "map")
    decoded = OccupancyGrid.decode(msg.encode())
    assert decoded.header.frame_id == "map" and decoded.header.stamp.to_sec() == pytest.approx(12.5)
    assert (decoded.info.width, decoded.info.height) == (occupancy.width, occupancy.height)
    back = occupancy_map_from_message(decoded)
    np.testing.assert_array_equal(back.data, occupancy.data)
    assert back.origin == pytest.approx(occupancy.origin)
    # Row 0 is the lowest y: the cell under (x, y) is data[iy * width + ix].
    ix, iy = occupancy.world_to_cell(-2.0, 3.8)  # inside the box
    assert decoded.data[iy * decoded.info.width + ix] == 100
    with pytest.raises(ValueError, match="cells for"):
        occupancy_map_from_message(OccupancyGrid(info=decoded.info, data=decoded.data[:-1]))


def test_costmap_and_path_messages() -> None:
    occupancy = OccupancyMap(0.1, (0.0, 0.0, 0.0), np.zeros((5, 6), dtype=np.int8))
    occupancy.data[2, 3] = 100
    grid = LayeredCostmap(occupancy, CostmapParams()).grid()
    msg = costmap_message(grid, 1.0, "map")
    data = np.asarray(msg.data).reshape(5, 6)
    assert data[2, 3] == 100 and data[2, 2] == 99 and data[0, 0] >= 0
    path = path_message(np.array([[0.0, 0.0, 0.0], [1.0, 0.5, math.pi / 2]]), 3.0, "map")
    decoded = Path.decode(path.encode())
    assert [p.pose.to_pose2d().yaw for p in decoded.poses] == pytest.approx([0.0, math.pi / 2])
    assert all(p.header.frame_id == "map" for p in decoded.poses)


# --- planning worker -------------------------------------------------------------------------------


def test_worker_delivers_paths_and_reasons_in_order() -> None:
    grid = _grid(_room(walls=[[[2.0, 0.0], [2.0, 3.0]]]))  # a wall right across the room
    outcomes: list[PlanOutcome] = []
    done = threading.Event()

    def deliver(outcome: PlanOutcome) -> None:
        outcomes.append(outcome)
        if len(outcomes) == 3:
            done.set()

    worker = PlanningWorker(GlobalPlannerParams(), deliver)
    try:
        worker.submit(PlanRequest(1, grid, Pose2D(0.5, 1.5, 0.0), Pose2D(1.5, 1.0, 0.0)))
        worker.submit(PlanRequest(2, grid, Pose2D(0.5, 1.5, 0.0), Pose2D(3.5, 1.5, 0.0)))
        worker.submit(PlanRequest(3, grid, Pose2D(0.5, 1.5, 0.0), Pose2D(9.0, 1.5, 0.0)))
        assert done.wait(10.0)
    finally:
        worker.close()
    assert [o.request.generation for o in outcomes] == [1, 2, 3]
    assert outcomes[0].path is not None and outcomes[0].path.poses[-1, :2] == pytest.approx([1.5, 1.0])
    assert outcomes[1].path is None and "no path" in outcomes[1].error and outcomes[1].blocked_end == ""
    assert outcomes[2].path is None and outcomes[2].blocked_end == "goal" and "outside" in outcomes[2].error


# --- shortest path yardstick -----------------------------------------------------------------------


def test_shortest_path_goes_round_walls_and_glass() -> None:
    open_room = _room()
    assert shortest_path_length_m(open_room, (0.5, 1.5), (3.5, 1.5)) == pytest.approx(3.0, abs=0.05)
    glass = load_world(GLASS_ROOM)
    straight = math.hypot(0.5 - -1.0, 1.5 - 4.2)
    around = shortest_path_length_m(glass, (-1.0, 4.2), (0.5, 1.5))
    # Round the east end of the pane (x = 1.6) keeping 0.15 m (3 cells) clear of its last cell.
    via_end = math.hypot(1.8 - -1.0, 2.75 - 4.2) + 0.3 + math.hypot(0.5 - 1.8, 1.5 - 2.45)
    assert around > straight + 1.0 and around == pytest.approx(via_end, abs=0.1)


# --- parameters ------------------------------------------------------------------------------------


def test_parameters_keep_costmap_follower_and_planner_in_agreement() -> None:
    params = Params(
        inflation_radius_m=0.7,
        cost_scaling_factor=4.0,
        robot_width_m=0.34,
        cost_weight=2.0,
        allow_unknown=True,
        max_linear_vel_mps=0.4,
    )
    costmap, follower, planner = params.costmap_params(), params.follower_params(), params.planner_params()
    assert follower.inflation_cost_scaling_factor == costmap.cost_scaling_factor == 4.0
    assert follower.inscribed_radius_m == costmap.inscribed_radius_m == pytest.approx(0.17)
    assert (follower.robot_length_m, follower.robot_width_m) == (
        costmap.robot_length_m,
        costmap.robot_width_m,
    )
    assert planner.astar.cost_weight == planner.smoothing.cost_weight == 2.0
    assert planner.astar.allow_unknown and planner.smoothing.allow_unknown
    assert follower.desired_linear_vel_mps == 0.4


def test_bad_parameters_are_refused() -> None:
    with pytest.raises(ValueError, match="lidar_mount"):
        Params(lidar_mount=(0.1, math.nan, 0.0))
    with pytest.raises(ConfigError, match="^params: max_linear_vel_mps: must be greater than 0.0$"):
        structs.validate(Params, {"max_linear_vel_mps": 0.0}, "params")
    with pytest.raises(ConfigError, match="^params: no_such_parameter: unknown key"):
        structs.validate(Params, {"no_such_parameter": 1}, "params")
    with pytest.raises(ValueError, match="(?s)map_yaml.*cannot read map file"):
        Params(map_yaml="/nonexistent/map.yaml")
    with pytest.raises(ValueError, match="(?s)world.*cannot read world file"):
        Params(world="/nonexistent/world.yaml")


# --- sonar and lidar -------------------------------------------------------------------------------


def _wall_hits(x0: float, x1: float, y: float, spacing_m: float = 0.03) -> np.ndarray:
    xs = np.arange(x0, x1, spacing_m)
    return np.stack([xs, np.full_like(xs, y)], axis=1)


def test_an_echo_from_a_wall_the_lidar_sees_is_explained() -> None:
    ahead = _wall_hits(-1.0, 1.0, 1.5)
    assert echo_explained_by_lidar((0.0, 0.0, math.pi / 2), 1.5, 0.5, ahead)


def test_a_corridor_side_wall_explains_the_echo_at_the_cone_edge() -> None:
    # Looking down a 1 m corridor (walls at y = +-0.5): the cone edge meets them about 2 m out,
    # while straight ahead the lidar sees 6 m of free corridor.
    sides = np.concatenate([_wall_hits(0.3, 6.0, 0.5, 0.12), _wall_hits(0.3, 6.0, -0.5, 0.12)])
    echo = 0.5 / math.sin(0.25)
    assert echo_explained_by_lidar((0.0, 0.0, 0.0), echo, 0.5, sides)


def test_a_wall_beside_a_panes_end_does_not_explain_the_ends_echo() -> None:
    # A wall 0.32 m to the right, parallel to the heading; a pane's end 0.9 m ahead, inside the cone. The
    # wall enters the cone (0.25 rad) 1.25 m out, so the 0.9 m echo is not the wall's: its nearest lidar
    # hit in the cone widened by two beams lies 1.16 m away. Widened by 0.1 rad, the wall's hits from 0.94 m
    # on had explained the echo, and the pane's end was cleared as floor.
    wall = _wall_hits(0.0, 4.0, -0.32, 0.01)
    assert not echo_explained_by_lidar((0.0, 0.0, 0.0), 0.9, 0.5, wall)
    assert echo_explained_by_lidar((0.0, 0.0, 0.0), 0.9, 0.5, wall, margin_rad=0.1)
    # The wall's own echo, from where the cone's edge meets it, is still the wall's.
    assert echo_explained_by_lidar((0.0, 0.0, 0.0), 0.32 / math.sin(0.25), 0.5, wall)


def test_glass_is_not_explained_by_what_the_lidar_sees_through_it() -> None:
    behind = _wall_hits(-1.0, 1.0, 3.5)  # the lidar's light went through the pane at 1.4 m
    assert not echo_explained_by_lidar((0.0, 0.0, math.pi / 2), 1.4, 0.5, behind)
    beside = _wall_hits(2.0, 3.0, 1.4)  # at the right range but far outside the cone
    assert not echo_explained_by_lidar((0.0, 0.0, math.pi / 2), 1.4, 0.5, beside)
    assert not echo_explained_by_lidar((0.0, 0.0, math.pi / 2), 1.4, 0.5, None)
    assert not echo_explained_by_lidar((0.0, 0.0, math.pi / 2), math.inf, 0.5, behind)


# --- glass memory ----------------------------------------------------------------------------------


def _glass_memory(suspicion_m: float) -> GlassMemory:
    frame = map_from_world(_room()).frame
    return GlassMemory(frame, CostmapParams(), suspicion_radius_m=suspicion_m)


def _is_glass(memory: GlassMemory, x: float, y: float) -> bool:
    ix, iy = memory.frame.world_to_cell(x, y)
    return bool(memory.glass_mask()[iy, ix])


def test_glass_memory_marks_echoes_and_suspects_only_floor_the_sonar_never_saw() -> None:
    memory = _glass_memory(suspicion_m=0.3)
    # Facing +x from (1.0, 1.5): a pane 1.0 m ahead, the cone 0.5 rad wide (the arc spans about +-0.25 m).
    memory.add_reading((1.0, 1.5, 0.0), 1.0, 0.5, 0.02, 3.0)
    assert _is_glass(memory, 2.0, 1.5)  # the echo itself
    assert not _is_glass(memory, 1.5, 1.5)  # looked through on the way
    # One echo marks the middle of the arc (its edges are less likely the echo's source) ...
    assert _is_glass(memory, 1.0 + math.sqrt(1.0 - 0.15**2), 1.5 + 0.15)  # on the arc, 0.15 rad off the axis
    assert _is_glass(memory, 2.0, 1.5 + 0.4)  # ... the pane may go on beyond what the cone covered ...
    assert _is_glass(memory, 2.2, 1.5)  # ... and behind it the sonar cannot look
    assert not _is_glass(memory, 2.0, 1.5 + 0.7)  # but not further than the suspicion radius
    # Looking along the suspected continuation from elsewhere clears it.
    memory.add_clear_view((2.0, 0.2, math.pi / 2), 2.0, 0.5, 0.02)
    assert not _is_glass(memory, 2.0, 1.0)
    # Where the robot stands there is no glass; clear() forgets everything.
    memory.observe_footprint((2.0, 1.5, 0.0))
    assert not _is_glass(memory, 2.0, 1.5)
    memory.clear()
    assert not memory.glass_mask().any()


def test_glass_memory_without_suspicion_keeps_only_the_marks() -> None:
    memory = _glass_memory(suspicion_m=0.0)
    memory.add_reading((1.0, 1.5, 0.0), 1.0, 0.5, 0.02, 3.0)
    assert _is_glass(memory, 2.0, 1.5) and not _is_glass(memory, 2.0, 1.5 + 0.45)
    memory.add_reading((1.0, 1.5, 0.0), math.inf, 0.5, 0.02, 3.0)  # no echo: the cone is clear ...
    assert not _is_glass(memory, 2.0, 1.5)
    # ... but only the cells it covers whole: those at the arc's ends lie partly outside it, and glass could
    # stand in their other part until a look covers them whole.
    memory.add_reading((1.0, 1.5 + 0.15, 0.0), math.inf, 0.5, 0.02, 3.0)
    memory.add_reading((1.0, 1.5 - 0.15, 0.0), math.inf, 0.5, 0.02, 3.0)
    assert not memory.glass_mask().any()
    with pytest.raises(ValueError, match="suspicion_radius_m"):
        GlassMemory(memory.frame, CostmapParams(), suspicion_radius_m=-1.0)


def test_heard_glass_near_a_point_is_what_the_whole_grid_holds_within_the_radius() -> None:
    """The slowdown asks only round the robot; the window must miss no heard cell within the radius, at
    the grid's edges too."""
    memory = _glass_memory(suspicion_m=0.3)
    memory.add_reading((1.0, 1.5, 0.0), 1.0, 0.5, 0.02, 3.0)  # marked
    memory.add_reading((1.0, 0.4, 0.3), 2.5, 0.5, 0.02, 3.0)  # heard, not marked
    every = memory.heard_cells_xy()
    assert len(every) > 10
    for near in ((2.0, 1.5), (0.0, 0.0), (3.2, 1.2), (1.5, 2.9), (-3.0, 1.0)):
        for radius in (0.05, 0.4, 1.0, 5.0):
            within = every[np.hypot(every[:, 0] - near[0], every[:, 1] - near[1]) <= radius]
            window = memory.heard_cells_xy(near, radius)
            kept = window[np.hypot(window[:, 0] - near[0], window[:, 1] - near[1]) <= radius]
            assert sorted(map(tuple, kept)) == sorted(map(tuple, within)), (near, radius)


def test_a_pane_heard_but_not_yet_marked_makes_the_floor_beyond_it_suspect() -> None:
    """Rounding a pane's end seen obliquely, the cells toward the end hold echoes too weak to mark (from
    the cone's edge, or from afar); the end lies beyond them. Suspicion grows from those heard cells as
    from marks, so the unlooked-at floor round the end counts as glass until the sonar looks there."""
    memory = _glass_memory(suspicion_m=0.3)
    memory.add_reading(
        (1.0, 1.5, 0.0), 2.5, 0.5, 0.02, 3.0
    )  # one far echo: an eighth of a near one's evidence
    assert (
        len(memory.heard_cells_xy()) > 0 and not (memory.sonar_layer == LETHAL_OBSTACLE).any()
    )  # heard, not marked
    assert _is_glass(memory, 3.5 + 0.25, 1.5)  # behind the echo the sonar could not look
    assert not _is_glass(memory, 3.0, 1.5)  # short of it the cone looked through
    without = _glass_memory(suspicion_m=0.0)
    without.add_reading((1.0, 1.5, 0.0), 2.5, 0.5, 0.02, 3.0)
    assert not without.glass_mask().any()


def test_a_robot_stopped_facing_glass_may_turn_where_it_stands_once_its_turning_circle_is_trusted() -> None:
    """The glass room's stuck start: 0.46 m from a pane, facing it. Beside the sonar's cone the floor was
    never looked at, so within the suspicion radius it counts as glass, within reach of the front corners."""
    memory = _glass_memory(suspicion_m=0.5)
    robot = (1.0, 1.5, 0.0)
    sensor = (1.2, 1.5, 0.0)  # the sonar sits at the front of the footprint
    memory.add_reading(sensor, 0.26, 0.5, 0.02, 3.0)  # the pane at x = 1.46
    memory.observe_footprint(robot)
    corner_sweep = (1.0 + 0.2, 1.5 + 0.2)  # where a front corner goes turning in place (radius 0.25 m)
    assert _is_glass(memory, *corner_sweep)
    memory.observe_turning_circle(robot)
    assert not _is_glass(memory, *corner_sweep)
    assert _is_glass(memory, 1.46, 1.5)  # the pane's marks stay
    assert _is_glass(memory, 1.46, 1.5 + 0.4)  # and so does the suspicion beyond the turning circle


def test_clearing_glass_round_the_robot_keeps_a_pane_seen_farther_away() -> None:
    memory = _glass_memory(suspicion_m=0.0)
    memory.add_reading((1.0, 1.5, 0.0), 0.4, 0.5, 0.02, 3.0)  # an echo 0.4 m ahead: within reach of a clear
    memory.add_reading((1.0, 1.0, 0.0), 1.6, 0.5, 0.02, 3.0)  # a pane seen 1.6 m away
    assert _is_glass(memory, 1.4, 1.5) and _is_glass(memory, 2.6, 1.0)
    memory.clear_around((1.0, 1.5), 1.0)
    assert not _is_glass(memory, 1.4, 1.5)
    assert _is_glass(memory, 2.6, 1.0)


def test_clearing_round_the_robot_keeps_the_glass_within_its_turning_reach() -> None:
    """A robot stuck 0.21 m beside a glass stub (generated room 168-2): forgotten, the stub was what it met
    next, turning to look round or driving off on a plan through it."""
    memory = _glass_memory(suspicion_m=0.0)
    memory.add_reading((1.0, 1.5, math.pi / 2), 0.21, 0.5, 0.02, 3.0)  # the stub, beside the robot
    memory.add_reading((1.0, 1.5, 0.0), 0.6, 0.5, 0.02, 3.0)  # an echo 0.6 m ahead
    assert _is_glass(memory, 1.0, 1.71) and _is_glass(memory, 1.6, 1.5)
    assert 0.21 < memory.turning_reach_m < 0.6
    memory.clear_around((1.0, 1.5), 1.0, keep_within_m=memory.turning_reach_m)
    assert _is_glass(memory, 1.0, 1.71), "the stub within the corners' reach was forgotten"
    assert not _is_glass(memory, 1.6, 1.5), "the echo beyond the reach should be forgotten"


def test_glass_a_clearing_forgot_comes_back_where_the_sonar_has_not_heard_since() -> None:
    """A look round that could not turn heard nothing again: a pane's end forgotten for want of that look
    was what the robot drove into next (generated room 103)."""
    memory = _glass_memory(suspicion_m=0.0)
    memory.add_reading((1.0, 1.5, 0.0), 0.6, 0.5, 0.02, 3.0)  # glass 0.6 m ahead
    memory.add_reading((1.0, 1.5, math.pi / 2), 0.6, 0.5, 0.02, 3.0)  # and 0.6 m to the left
    assert _is_glass(memory, 1.6, 1.5) and _is_glass(memory, 1.0, 2.1)
    memory.clear_around((1.0, 1.5), 1.0, keep_within_m=memory.turning_reach_m)
    assert not _is_glass(memory, 1.6, 1.5) and not _is_glass(memory, 1.0, 2.1)
    memory.add_reading((1.0, 1.5, 0.0), 3.0, 0.5, 0.02, 3.0)  # looked ahead again: nothing there now
    assert memory.restore_unheard() > 0
    assert not _is_glass(memory, 1.6, 1.5), "what the sonar heard since the clearing stands"
    assert _is_glass(memory, 1.0, 2.1), "the glass nobody looked at again is back"
    assert memory.restore_unheard() == 0, "one clearing is put back once"


def _slows_near(memory: GlassMemory, x: float, y: float) -> bool:
    """Whether the robot slows for glass in the cell of ``(x, y)`` (:meth:`GlassMemory.heard_cells_xy`)."""
    heard = memory.heard_cells_xy()
    return bool(len(heard)) and float(np.min(np.hypot(heard[:, 0] - x, heard[:, 1] - y))) < 0.05


@pytest.mark.parametrize("clearing", ["around", "all", "square"])
def test_the_robot_slows_near_forgotten_glass_until_the_sonar_looks_there_again(clearing: str) -> None:
    """A clearing forgets glass so that a plan may pass where a spurious echo stood; a pane's end forgotten
    that way and not heard again was driven into at 0.35 m/s (generated room 103)."""
    memory = _glass_memory(suspicion_m=0.0)
    memory.add_reading((1.0, 1.5, 0.0), 0.6, 0.5, 0.02, 3.0)  # glass 0.6 m ahead
    assert _is_glass(memory, 1.6, 1.5) and _slows_near(memory, 1.6, 1.5)
    if clearing == "around":
        memory.clear_around((1.0, 1.5), 1.0, keep_within_m=memory.turning_reach_m)
    elif clearing == "all":
        memory.clear()
    else:
        memory.clear_cells(memory.frame.cells_within((1.6, 1.5), 0.3))
    assert not _is_glass(memory, 1.6, 1.5), "forgotten: the planner may pass"
    assert _slows_near(memory, 1.6, 1.5), "but not at full speed"
    memory.add_reading((1.0, 1.5, 0.0), 3.0, 0.5, 0.02, 3.0)  # looked again: nothing there now
    assert not _slows_near(memory, 1.6, 1.5)
    memory.clear()  # a later clearing does not bring back what the sonar has since found free
    assert not _slows_near(memory, 1.6, 1.5)


def test_glass_cleared_on_request_or_all_at_once_is_not_put_back() -> None:
    memory = _glass_memory(suspicion_m=0.0)
    memory.add_reading((1.0, 1.5, 0.0), 0.6, 0.5, 0.02, 3.0)
    memory.clear_around((1.0, 1.5), 1.0, keep_within_m=memory.turning_reach_m)
    memory.clear()  # a recovery that forgot everything (or Nav2's clear_entirely): nothing to put back
    assert memory.restore_unheard() == 0 and not _is_glass(memory, 1.6, 1.5)
    memory.add_reading((1.0, 1.5, 0.0), 0.6, 0.5, 0.02, 3.0)
    memory.clear_around((1.0, 1.5), 1.0, keep_within_m=memory.turning_reach_m)
    memory.clear_cells(memory.frame.cells_within((1.6, 1.5), 0.2))  # a region clear asked for since
    assert memory.restore_unheard() == 0 and not _is_glass(memory, 1.6, 1.5)


def test_recoveries_forget_glass_round_the_robot_and_all_of_it_only_when_no_path_is_found_again() -> None:
    kept, around, everything = GlassClearing.KEEP, GlassClearing.AROUND_ROBOT, GlassClearing.ALL
    # following failed (blocked, stuck): a pane's end seen once stays known however often it fails
    assert [glass_clearing(n, planning_failed=False) for n in range(1, 7)] == [kept, around] * 3
    # no path: round the robot first; glass farther off can block the only way, so then all of it
    assert [glass_clearing(n, planning_failed=True) for n in range(1, 7)] == [
        kept,
        around,
        kept,
        everything,
        kept,
        everything,
    ]


def test_follower_settings_come_from_the_planner_parameters() -> None:
    follower = Params().follower_params()
    assert follower.approach_velocity_scaling_dist_m == pytest.approx(0.3)
    assert follower.regulated_linear_scaling_min_radius_m == pytest.approx(0.6)
    assert follower.approach_decel_mps2 == pytest.approx(0.75)
    tuned = Params(
        approach_velocity_scaling_dist_m=0.6, regulated_linear_scaling_min_radius_m=0.9
    ).follower_params()
    assert (tuned.approach_velocity_scaling_dist_m, tuned.regulated_linear_scaling_min_radius_m) == (0.6, 0.9)
    params = Params()
    assert params.open_loop_acceleration and params.carried_pose_timeout_s > params.pose_timeout_s
