"""The robot in the pymunk room: kinematics, limits, solid walls and glass, teleport, localisation."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import pytest

from services.simulator.localisation import map_to_odom
from services.simulator.physics import PoseInCollisionError, Robot, SimParams
from shared.geometry import Pose2D, wrap_angle
from shared.world import ROBOT_FRONT_M, World, load_world


def drive(sim: Robot, v: float, w: float, seconds: float) -> None:
    for _ in range(round(seconds / sim.params.dt_s)):
        sim.step(v, w)


def test_drives_straight_as_the_kinematics_say(quiet: SimParams, open_world: Callable[..., World]) -> None:
    sim = Robot(open_world(), params=quiet)
    drive(sim, 0.3, 0.0, 3.0)
    # Ramp at 1 m/s^2 to 0.3 m/s costs 0.3^2 / 2 m; the base answers one 10 ms step late.
    expected_x = 0.3 * 3.0 - 0.3**2 / 2.0 - 0.3 * 0.01
    assert sim.pose.x == pytest.approx(expected_x, abs=0.003)
    assert sim.pose.y == pytest.approx(0.0, abs=1e-9)
    assert sim.pose.yaw == pytest.approx(0.0, abs=1e-9)
    assert sim.twist.linear_mps == pytest.approx(0.3)
    assert sim.odom_pose.x == pytest.approx(sim.pose.x, abs=1e-9)


def test_turns_in_place_as_the_kinematics_say(quiet: SimParams, open_world: Callable[..., World]) -> None:
    sim = Robot(open_world(), params=quiet)
    drive(sim, 0.0, 1.0, 2.0)
    expected_yaw = 1.0 * 2.0 - 1.0**2 / (2.0 * 3.0) - 1.0 * 0.01
    assert sim.pose.yaw == pytest.approx(expected_yaw, abs=0.01)
    assert math.hypot(sim.pose.x, sim.pose.y) < 1e-9
    assert sim.odom_pose.yaw == pytest.approx(sim.pose.yaw, abs=1e-9)


def test_arc_stays_on_its_circle(quiet: SimParams, open_world: Callable[..., World]) -> None:
    sim = Robot(open_world(), params=quiet)
    v, w = 0.2, 0.5
    radius = v / w
    drive(sim, v, w, 1.0)  # past both acceleration ramps
    start = sim.pose
    cx, cy = start.x - radius * math.sin(start.yaw), start.y + radius * math.cos(start.yaw)
    for _ in range(30):
        drive(sim, v, w, 0.1)
        assert math.hypot(sim.pose.x - cx, sim.pose.y - cy) == pytest.approx(radius, abs=1e-6)
    assert wrap_angle(sim.pose.yaw - start.yaw) == pytest.approx(w * 3.0, abs=1e-6)
    # The odom frame starts at the start pose (the origin here): odometry follows the truth exactly.
    assert sim.odom_pose.as_tuple() == pytest.approx(sim.pose.as_tuple(), abs=1e-9)
    assert sim.map_to_odom().compose(sim.odom_pose).distance_to(sim.pose) < 1e-9


def test_acceleration_limits_hold_in_the_body_motion(
    quiet: SimParams, open_world: Callable[..., World]
) -> None:
    sim = Robot(open_world(), params=quiet)
    previous = sim.twist
    for command in [(0.5, 1.5)] * 80 + [(-0.5, -1.5)] * 120:
        sim.step(*command)
        dv = abs(sim.twist.linear_mps - previous.linear_mps)
        dw = abs(sim.twist.angular_radps - previous.angular_radps)
        assert dv <= 1.0 * 0.01 + 1e-9
        assert dw <= 3.0 * 0.01 + 1e-9
        previous = sim.twist
    assert previous.linear_mps < 0 and previous.angular_radps < 0


@pytest.mark.parametrize("kind", ["walls", "glass"])
def test_cannot_pass_through_a_wall_or_glass(
    kind: str, quiet: SimParams, open_world: Callable[..., World]
) -> None:
    sim = Robot(open_world(**{kind: [[[2.0, -1.0], [2.0, 1.0]]]}), params=quiet)
    drive(sim, 0.5, 0.0, 8.0)
    front_x = sim.pose.x + ROBOT_FRONT_M
    assert 2.0 - 0.005 <= front_x <= 2.0 + 0.002
    events = sim.drain_collisions()
    assert [e.kind for e in events] == ["wall" if kind == "walls" else "glass"]
    assert events[0].speed_mps == pytest.approx(0.5, abs=0.01)
    assert events[0].x_m == pytest.approx(2.0, abs=0.005)
    drive(sim, 0.5, 0.0, 2.0)  # keeps pushing: still one collision
    assert sim.drain_collisions() == []
    drive(sim, -0.3, 0.0, 1.0)
    drive(sim, 0.3, 0.0, 3.0)  # backs off and hits again: a second one
    assert len(sim.drain_collisions()) == 1


def test_glass_partition_stops_the_robot_in_the_glass_room(quiet: SimParams, worlds_dir: Path) -> None:
    sim = Robot(load_world(worlds_dir / "glass_room.yaml"), params=quiet)
    drive(sim, 0.5, 0.0, 6.0)
    assert sim.pose.y - ROBOT_FRONT_M == pytest.approx(2.6, abs=0.005)
    assert sim.collision_counts["glass"] == 1
    assert [e.kind for e in sim.drain_collisions()] == ["glass"]


def test_sliding_along_a_wall_keeps_out_of_it(quiet: SimParams, open_world: Callable[..., World]) -> None:
    sim = Robot(open_world(walls=[[[-3.0, 1.0], [3.0, 1.0]]]), params=quiet)
    sim.teleport(Pose2D(-2.0, 0.5, 0.5))
    drive(sim, 0.4, 0.0, 6.0)
    corners_y = [sim.pose.transform_point(px, py)[1] for px in (-0.2, 0.2) for py in (-0.15, 0.15)]
    assert max(corners_y) <= 1.0 + 0.002


@pytest.mark.parametrize(
    ("pose", "what"),
    [
        (Pose2D(1.5, 3.2, 0.0), "wall"),
        (Pose2D(-2.0, 3.6, 0.3), "box"),
        (Pose2D(-1.0, 0.75, -math.pi / 2), "dock 'home'"),
        (Pose2D(-2.9, 2.0, 0.0), "wall"),
    ],
)
def test_teleport_into_an_obstacle_is_rejected(pose: Pose2D, what: str, worlds_dir: Path) -> None:
    sim = Robot(load_world(worlds_dir / "seed_room.yaml"))
    before = sim.pose
    with pytest.raises(PoseInCollisionError, match=what):
        sim.teleport(pose)
    assert sim.pose == before


def test_teleport_outside_the_room_is_rejected_and_a_free_pose_accepted(worlds_dir: Path) -> None:
    sim = Robot(load_world(worlds_dir / "seed_room.yaml"))
    with pytest.raises(PoseInCollisionError, match="outside the room"):
        sim.teleport(Pose2D(10.0, 2.0, 0.0))
    drive(sim, 0.3, 0.2, 1.0)
    sim.teleport(Pose2D(0.0, 2.0, 1.0))
    assert sim.pose.as_tuple() == pytest.approx((0.0, 2.0, 1.0))
    assert sim.odom_pose == Pose2D() and sim.twist.linear_mps == 0.0
    sim.step(0.0, 0.0)
    assert sim.pose.as_tuple() == pytest.approx((0.0, 2.0, 1.0))  # a teleported robot stands still


def test_start_pose_in_collision_is_rejected(open_world: Callable[..., World]) -> None:
    world = open_world(boxes=[{"pose": [0.0, 0.0, 0.0], "size": [0.5, 0.5]}])
    with pytest.raises(PoseInCollisionError, match="box"):
        Robot(world)


def test_map_to_odom_lands_on_true_pose_times_error() -> None:
    true_pose, odom = Pose2D(1.0, 2.0, 0.7), Pose2D(-0.3, 0.4, -2.5)
    error = Pose2D(0.05, -0.02, 0.03)
    assert map_to_odom(true_pose, odom).compose(odom).as_tuple() == pytest.approx(true_pose.as_tuple())
    believed = map_to_odom(true_pose, odom, error).compose(odom)
    # Ahead by 5 cm and left... in the robot's frame: yaw 0.7 rotates the offset into the map.
    expected = (
        1.0 + 0.05 * math.cos(0.7) + 0.02 * math.sin(0.7),
        2.0 + 0.05 * math.sin(0.7) - 0.02 * math.cos(0.7),
        0.73,
    )
    assert believed.as_tuple() == pytest.approx(expected)


def test_localisation_absorbs_odometry_drift_but_keeps_its_error(open_world: Callable[..., World]) -> None:
    error = Pose2D(0.1, 0.0, 0.05)
    sim = Robot(open_world(), params=SimParams(odom_noise=0.05, localisation_error=error))
    drive(sim, 0.4, 0.6, 5.0)
    assert sim.odom_pose.distance_to(Pose2D()) > 0.5
    assert sim.odom_pose.distance_to(sim.pose) > 1e-3  # noisy wheels: odometry has drifted from the truth
    believed = sim.map_to_odom().compose(sim.odom_pose)
    assert believed.as_tuple() == pytest.approx(sim.pose.compose(error).as_tuple(), abs=1e-9)


def test_an_initial_pose_becomes_the_belief_and_its_offset_the_error(
    open_world: Callable[..., World],
) -> None:
    sim = Robot(open_world(), params=SimParams(odom_noise=0.05))
    drive(sim, 0.3, 0.4, 2.0)
    given = sim.pose.compose(Pose2D(0.2, -0.1, 0.3))
    sim.believe(given)
    believed = sim.map_to_odom().compose(sim.odom_pose)
    assert believed.as_tuple() == pytest.approx(given.as_tuple(), abs=1e-9)
    drive(sim, 0.3, 0.0, 1.0)  # the offset stays with the robot as it moves (the localiser does not converge)
    believed = sim.map_to_odom().compose(sim.odom_pose)
    assert believed.as_tuple() == pytest.approx(sim.pose.compose(Pose2D(0.2, -0.1, 0.3)).as_tuple(), abs=1e-9)


def test_wiggling_against_a_wall_is_one_collision(quiet: SimParams, open_world: Callable[..., World]) -> None:
    sim = Robot(open_world(walls=[[[-3.0, 1.0], [3.0, 1.0]]]), params=quiet)
    sim.teleport(Pose2D(0.0, 0.75, math.pi / 2))
    drive(sim, 0.2, 0.0, 3.0)
    for i in range(600):  # nudging forward while swinging left and right: corners leave and touch again
        sim.step(0.05, math.sin(0.05 * i))
    assert [e.kind for e in sim.drain_collisions()] == ["wall"]
