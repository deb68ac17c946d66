"""Regulated Pure Pursuit: steering geometry, regulation, rotate-in-place, goal handling, collisions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from services.planner.costmap import CostmapParams, LayeredCostmap
from services.planner.occupancy_map import OCC_FREE, OCC_OCCUPIED, OccupancyMap
from services.planner.pure_pursuit import (
    APPROACH_STOP_SHORT,
    FollowStatus,
    PurePursuitParams,
    RegulatedPurePursuit,
    circle_segment_intersection,
    cost_regulated_speed,
    curvature_to,
    project_arc,
)
from shared.geometry import Pose2D, wrap_angle

DT = 0.05


def _straight(length_m: float = 3.0, yaw: float = 0.0) -> np.ndarray:
    s = np.arange(0.0, length_m + 1e-9, 0.05)
    return np.column_stack([s * math.cos(yaw), s * math.sin(yaw), np.full(len(s), yaw)])


def _arc(radius_m: float, sweep_rad: float, left: bool = True) -> np.ndarray:
    """An arc starting at the origin heading +x, turning left (or right)."""
    sign = 1.0 if left else -1.0
    t = np.linspace(0.0, sweep_rad, max(3, int(radius_m * sweep_rad / 0.05)))
    x = radius_m * np.sin(t)
    y = sign * radius_m * (1.0 - np.cos(t))
    return np.column_stack([x, y, sign * t])


def _follower(path: np.ndarray, **overrides: object) -> RegulatedPurePursuit:
    follower = RegulatedPurePursuit(PurePursuitParams(**overrides))  # type: ignore[arg-type]
    follower.set_path(path)
    return follower


def _drive(pose: Pose2D, v: float, w: float, dt: float = DT) -> Pose2D:
    x, y, yaw = project_arc(pose, v, w, np.array([dt]))[0]
    return Pose2D(float(x), float(y), wrap_angle(float(yaw)))


def _free_costmap(size_m: float = 6.0, origin: float = -3.0) -> LayeredCostmap:
    n = int(size_m / 0.05)
    grid = OccupancyMap(0.05, (origin, origin, 0.0), np.full((n, n), OCC_FREE, dtype=np.int8))
    return LayeredCostmap(grid)


def test_geometry_helpers() -> None:
    assert curvature_to(1.0, 0.0) == 0.0
    assert curvature_to(1.0, 1.0) == pytest.approx(1.0)  # the unit circle through (1, 1)
    assert curvature_to(0.5, -0.5) == pytest.approx(-2.0)
    hit = circle_segment_intersection(np.array([0.2, 0.0]), np.array([2.0, 0.0]), 1.0)
    assert hit == pytest.approx([1.0, 0.0])
    end = project_arc(Pose2D(0.0, 0.0, 0.0), 0.5, 0.5, np.array([2 * math.pi]))[0]
    assert end == pytest.approx([0.0, 2.0, math.pi], abs=1e-9)  # half a circle of radius 1


def test_straight_path_drives_straight() -> None:
    command = _follower(_straight()).compute_velocity_command(Pose2D(0.0, 0.0, 0.0), (0.5, 0.0), DT)
    assert command.status is FollowStatus.FOLLOWING
    assert command.linear_mps == pytest.approx(0.5)
    assert command.angular_radps == pytest.approx(0.0, abs=1e-9)
    assert command.lookahead_point == pytest.approx((0.75, 0.0))  # 0.5 m/s * 1.5 s


def test_a_speed_limit_caps_the_forward_speed() -> None:
    follower = _follower(_straight())
    speed = 0.5
    for _ in range(10):  # braking within the deceleration limit, then held at the limit
        command = follower.compute_velocity_command(
            Pose2D(0.0, 0.0, 0.0), (speed, 0.0), DT, speed_limit_mps=0.2
        )
        assert command.status is FollowStatus.FOLLOWING and command.linear_mps < speed or speed <= 0.2
        speed = command.linear_mps
    assert speed == pytest.approx(0.2)


def test_path_curving_left_turns_left_and_right_turns_right() -> None:
    for left in (True, False):
        command = _follower(_arc(1.5, 2.0, left)).compute_velocity_command(Pose2D(0, 0, 0), (0.4, 0.0), DT)
        assert command.status is FollowStatus.FOLLOWING
        assert (command.angular_radps > 0.1) if left else (command.angular_radps < -0.1)
        # On an arc of radius 1.5 the pursuit arc has about the same curvature.
        assert abs(command.curvature) == pytest.approx(1 / 1.5, rel=0.05)


def test_robot_beside_the_path_steers_back_onto_it() -> None:
    command = _follower(_straight()).compute_velocity_command(Pose2D(0.0, 0.3, 0.0), (0.3, 0.0), DT)
    assert command.angular_radps < 0.0


def test_lookahead_grows_with_speed_within_limits() -> None:
    follower = _follower(_straight(5.0))
    dists = [
        follower.compute_velocity_command(Pose2D(0, 0, 0), (v, 0.0), DT).lookahead_point[0]
        for v in (0.0, 0.3, 0.5, 2.0)
    ]
    assert dists == pytest.approx([0.3, 0.45, 0.75, 0.9])


def test_tight_curves_are_taken_slower() -> None:
    gentle = _follower(_arc(3.0, 1.0)).compute_velocity_command(Pose2D(0, 0, 0), (0.5, 0.0), DT)
    tight = _follower(_arc(0.4, 1.5)).compute_velocity_command(Pose2D(0, 0, 0), (0.5, 0.0), DT)
    assert gentle.linear_mps == pytest.approx(0.5)
    assert 0.25 <= tight.linear_mps < 0.45
    assert abs(tight.angular_radps) <= 1.5


def test_cost_regulation_slows_near_obstacles() -> None:
    params = PurePursuitParams()
    assert cost_regulated_speed(0, 0.5, params) == 0.5
    assert cost_regulated_speed(255, 0.5, params) == 0.5
    # Cost 100 means 0.15 + ln(2.52) / 3 = 0.458 m from an obstacle, inside the 0.6 m scaling distance.
    assert cost_regulated_speed(100, 0.5, params) == pytest.approx(0.5 * (0.15 + math.log(2.52) / 3) / 0.6)
    costmap = _free_costmap()
    costmap.update_with_scan((0.0, 0.0), np.array([[1.5, 0.45]]))  # an obstacle 0.45 m beside the path
    follower = _follower(_straight())
    near = follower.compute_velocity_command(Pose2D(1.5, 0.0, 0.0), (0.5, 0.0), DT, costmap.grid())
    assert near.status is FollowStatus.FOLLOWING
    assert 0.25 <= near.linear_mps < 0.45


def test_slows_on_the_final_approach() -> None:
    follower = _follower(_straight(2.0))
    far = follower.compute_velocity_command(Pose2D(0.5, 0.0, 0.0), (0.5, 0.0), DT)
    near = follower.compute_velocity_command(Pose2D(1.85, 0.0, 0.0), (0.1, 0.0), DT)
    assert far.linear_mps == pytest.approx(0.5)
    assert near.linear_mps == pytest.approx(0.5 * 0.15 / 0.6)  # 0.15 m left of the 0.6 m approach
    braking = follower.compute_velocity_command(Pose2D(1.85, 0.0, 0.0), (0.5, 0.0), DT)
    assert braking.linear_mps == pytest.approx(0.5 - 1.5 * DT)  # no harder than max_linear_decel


def test_the_braking_approach_keeps_full_speed_until_the_brake_must_start() -> None:
    follower = _follower(_straight(2.0), approach_decel_mps2=0.75)
    far = follower.compute_velocity_command(Pose2D(1.5, 0.0, 0.0), (0.5, 0.0), DT)
    assert far.linear_mps == pytest.approx(0.5)  # 0.5 m left: the Nav2 law would be slowing already
    near = follower.compute_velocity_command(Pose2D(1.85, 0.0, 0.0), (0.5, 0.0), DT)
    short_m = APPROACH_STOP_SHORT * follower.params.xy_goal_tolerance_m
    assert near.linear_mps == pytest.approx(math.sqrt(2.0 * 0.75 * (0.15 - short_m)))


def _time_to_the_goal(follower: RegulatedPurePursuit, pose: Pose2D, v: float) -> tuple[float, Pose2D]:
    """Drive the follower's commands exactly until it says the goal is reached (sim seconds)."""
    t = 0.0
    w = 0.0
    while t < 30.0:
        command = follower.compute_velocity_command(pose, (v, w), DT)
        if command.status is FollowStatus.GOAL_REACHED:
            return t, pose
        v, w = command.linear_mps, command.angular_radps
        pose = _drive(pose, v, w)
        t += DT
    raise AssertionError(f"the goal was not reached in 30 s; the robot is at {pose}")


def test_the_braking_approach_arrives_sooner_and_inside_the_tolerance() -> None:
    nav2_s, _ = _time_to_the_goal(_follower(_straight(2.0)), Pose2D(0.0, 0.0, 0.0), 0.5)
    braking = _follower(_straight(2.0), approach_decel_mps2=0.75)
    braking_s, end = _time_to_the_goal(braking, Pose2D(0.0, 0.0, 0.0), 0.5)
    assert braking_s < nav2_s - 0.3, (braking_s, nav2_s)
    assert 2.0 - braking.params.xy_goal_tolerance_m <= end.x <= 2.0  # inside the tolerance, not past the goal


def test_acceleration_limits_from_rest() -> None:
    command = _follower(_straight()).compute_velocity_command(Pose2D(0, 0, 0), (0.0, 0.0), DT)
    assert command.linear_mps == pytest.approx(1.0 * DT)


def test_rotates_in_place_when_facing_away() -> None:
    follower = _follower(_straight())
    command = follower.compute_velocity_command(Pose2D(0.0, 0.0, math.pi / 2), (0.0, 0.0), DT)
    assert command.status is FollowStatus.ROTATING_TO_PATH
    assert command.linear_mps == 0.0
    assert command.angular_radps == pytest.approx(-3.2 * DT)  # clockwise, accel-limited from rest
    spinning = follower.compute_velocity_command(Pose2D(0.0, 0.0, math.pi / 2), (0.0, -1.5), DT)
    assert spinning.angular_radps == pytest.approx(-1.5)


def test_reaches_the_goal_then_turns_to_its_yaw_and_stops() -> None:
    path = _straight(1.0)
    path[-1, 2] = math.pi / 2  # arrive facing +y
    follower = _follower(path)
    pose, v, w = Pose2D(0.0, 0.05, 0.0), 0.0, 0.0
    statuses = []
    for _ in range(400):
        command = follower.compute_velocity_command(pose, (v, w), DT)
        statuses.append(command.status)
        if command.status is FollowStatus.GOAL_REACHED:
            break
        v, w = command.linear_mps, command.angular_radps
        assert abs(w) <= 1.5 + 1e-9 and 0.0 <= v <= 0.5 + 1e-9
        pose = _drive(pose, v, w)
    assert statuses[-1] is FollowStatus.GOAL_REACHED
    assert FollowStatus.ROTATING_TO_GOAL in statuses
    assert math.hypot(pose.x - 1.0, pose.y) <= 0.05
    assert abs(wrap_angle(pose.yaw - math.pi / 2)) <= 0.05
    assert (command.linear_mps, command.angular_radps) == (0.0, 0.0)
    # Goal reached latches: drifting a little outside the xy tolerance does not restart the approach.
    assert follower.compute_velocity_command(Pose2D(1.06, 0.0, math.pi / 2), (0, 0), DT).status is (
        FollowStatus.GOAL_REACHED
    )
    assert follower.confirm_goal(Pose2D(1.06, 0.0, math.pi / 2))  # ... and stopped there it has arrived


def test_stopped_well_past_the_goal_it_has_not_arrived_and_turns_back() -> None:
    """Braking from inside the tolerance can carry a robot past it under load: once stopped, it is judged
    again, and the follower drives back instead of reporting arrival."""
    follower = _follower(_straight(1.0))
    arrived = follower.compute_velocity_command(Pose2D(0.97, 0.0, 0.0), (0.05, 0.0), DT)
    assert arrived.status is FollowStatus.GOAL_REACHED  # inside 0.05 m: the tolerance latches
    past = Pose2D(1.1, 0.0, 0.0)
    assert follower.compute_velocity_command(past, (0.0, 0.0), DT).status is FollowStatus.GOAL_REACHED
    assert not follower.confirm_goal(past) and not follower.xy_goal_reached
    back = follower.compute_velocity_command(past, (0.0, 0.0), DT)
    assert back.status is not FollowStatus.GOAL_REACHED and back.angular_radps != 0.0  # turning round


def test_follows_a_curved_path_to_the_end() -> None:
    path = np.concatenate([_straight(1.0), _arc(1.0, math.pi / 2)[1:] + [1.0, 0.0, 0.0]])
    follower = _follower(path)
    pose, v, w = Pose2D(0.0, 0.0, 0.0), 0.0, 0.0
    worst_offset = 0.0
    for _ in range(600):
        command = follower.compute_velocity_command(pose, (v, w), DT)
        if command.status is FollowStatus.GOAL_REACHED:
            break
        v, w = command.linear_mps, command.angular_radps
        pose = _drive(pose, v, w)
        worst_offset = max(worst_offset, float(np.min(np.hypot(path[:, 0] - pose.x, path[:, 1] - pose.y))))
    assert command.status is FollowStatus.GOAL_REACHED
    assert math.hypot(pose.x - path[-1, 0], pose.y - path[-1, 1]) <= 0.05
    assert worst_offset < 0.1


def test_stops_for_an_obstacle_ahead_but_not_one_beyond_reach() -> None:
    costmap = _free_costmap()
    follower = _follower(_straight(2.5), use_cost_regulated_linear_velocity_scaling=False)
    costmap.update_with_scan((0.0, 0.0), np.array([[0.55, 0.0]]))  # footprint front at 0.2 m: 0.35 m to go
    blocked = follower.compute_velocity_command(Pose2D(0, 0, 0), (0.5, 0.0), DT, costmap.grid())
    assert blocked.status is FollowStatus.COLLISION_AHEAD
    assert (blocked.linear_mps, blocked.angular_radps) == (0.0, 0.0)
    costmap.clear()
    costmap.update_with_scan((0.0, 0.0), np.array([[1.6, 0.0]]))  # more than 1 s at 0.5 m/s away
    clear = follower.compute_velocity_command(Pose2D(0, 0, 0), (0.5, 0.0), DT, costmap.grid())
    assert clear.status is FollowStatus.FOLLOWING and clear.linear_mps > 0.4


def test_rotation_in_place_is_checked_for_collisions() -> None:
    grid = OccupancyMap(0.05, (-1.0, -1.0, 0.0), np.full((40, 40), OCC_FREE, dtype=np.int8))
    grid.data[20, 24] = OCC_OCCUPIED  # 0.225 m straight ahead: the footprint corners sweep through it
    costmap = LayeredCostmap(grid, CostmapParams(inflation_radius_m=0.0)).grid()
    follower = _follower(_straight(1.0, yaw=math.pi / 2))
    command = follower.compute_velocity_command(Pose2D(0.0, 0.0, -0.4), (0.0, 1.5), DT, costmap)
    assert command.status is FollowStatus.COLLISION_AHEAD


def test_no_path_and_reset() -> None:
    follower = RegulatedPurePursuit()
    assert follower.compute_velocity_command(Pose2D(), (0, 0), DT).status is FollowStatus.NO_PATH
    follower.set_path(_straight())
    assert follower.compute_velocity_command(Pose2D(), (0.5, 0), DT).status is FollowStatus.FOLLOWING
    follower.reset()
    assert follower.compute_velocity_command(Pose2D(), (0.5, 0), DT).status is FollowStatus.NO_PATH


def test_params_are_validated() -> None:
    with pytest.raises(ValueError, match="desired_linear_vel_mps"):
        PurePursuitParams(desired_linear_vel_mps=0.0)
    with pytest.raises(ValueError, match="min_lookahead_dist_m"):
        PurePursuitParams(min_lookahead_dist_m=1.0, max_lookahead_dist_m=0.5)
    with pytest.raises(ValueError, match="xy_goal_tolerance_m"):
        PurePursuitParams(xy_goal_tolerance_m=-0.1)
