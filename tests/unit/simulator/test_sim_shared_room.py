"""Several robots in one room: one space, so they collide with and see each other."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from services.simulator.physics import PoseInCollisionError, Robot, SimParams, step_together
from shared.geometry import Pose2D
from shared.world import World


def _drive_together(robots: list[Robot], commands: list[tuple[float, float]], seconds: float) -> None:
    for _ in range(round(seconds / robots[0].params.dt_s)):
        step_together(robots, commands)


def test_two_robots_head_on_collide_and_each_names_the_other(
    quiet: SimParams, open_world: Callable[..., World]
) -> None:
    world = open_world()
    r1 = Robot(world, params=quiet, start=Pose2D(-1.0, 0.0, 0.0), name="r1")
    r2 = r1.join("r2", Pose2D(1.0, 0.0, math.pi))
    assert r1.members == [r1, r2] and r2.space is r1.space
    _drive_together([r1, r2], [(0.4, 0.0), (0.4, 0.0)], 4.0)
    gap = r2.pose.x - r1.pose.x
    assert gap == pytest.approx(0.40, abs=0.01), "they stop against each other, front to front"
    e1, e2 = r1.drain_collisions(), r2.drain_collisions()
    assert [(e.kind, e.other_robot) for e in e1] == [("robot", "r2")]
    assert [(e.kind, e.other_robot) for e in e2] == [("robot", "r1")]
    assert e1[0].x_m == pytest.approx(0.5 * (r1.pose.x + r2.pose.x), abs=0.02)
    assert e1[0].speed_mps == pytest.approx(0.8, abs=0.15), "the closing speed"
    assert r1.collision_counts["robot"] == 1 and r1.collision_counts["wall"] == 0


def test_each_robots_sensors_see_the_others_body(quiet: SimParams, open_world: Callable[..., World]) -> None:
    world = open_world()
    r1 = Robot(world, params=quiet, start=Pose2D(0.0, 0.0, 0.0), name="r1")
    alone = Robot(world, params=quiet, start=Pose2D(0.0, 0.0, 0.0))
    r1.join("r2", Pose2D(2.0, 0.0, math.pi / 2))  # broadside, 2 m ahead: its near side at x = 1.85
    assert r1.ultrasonic_range() == pytest.approx(1.85 - 0.20, abs=1e-6)
    forward = r1.params.lidar.num_rays // 2
    assert r1.lidar_scan().ranges_m[forward] == pytest.approx(1.85 - 0.10, abs=1e-6)
    assert math.isinf(alone.ultrasonic_range()), "alone, nothing within its 3 m range"
    assert np.isfinite(r1.lidar_scan().ranges_m).sum() >= np.isfinite(alone.lidar_scan().ranges_m).sum()


def _edges_by_hand(robot: Robot) -> np.ndarray:
    """The other robots' footprint edges as ``(M, 2, 2)`` start/end points, built afresh."""
    return np.array(
        [
            (c[i], c[(i + 1) % 4])
            for m in robot.members
            if m is not robot
            for c in [m.footprint()]
            for i in range(4)
        ]
    )


def test_what_sensors_see_of_the_others_follows_every_move(
    quiet: SimParams, open_world: Callable[..., World]
) -> None:
    world = open_world()
    r1 = Robot(world, params=quiet, start=Pose2D(0.0, 0.0, 0.0), name="r1")
    r2 = r1.join("r2", Pose2D(2.0, 0.0, math.pi / 2))
    r3 = r1.join("r3", Pose2D(0.0, 2.0, 0.0))  # joined after r1's edges may have been built

    def check() -> None:
        for robot in (r1, r2, r3):
            seen = robot.room.with_others(robot, robot.opaque)
            static = len(robot.opaque)
            expected = _edges_by_hand(robot)
            assert np.array_equal(seen.start[:static], robot.opaque.start)
            assert np.array_equal(seen.start[static:], expected[:, 0])
            assert np.array_equal(seen.delta[static:], expected[:, 1] - expected[:, 0])

    check()
    _drive_together([r1, r2, r3], [(0.3, 0.5), (0.2, -0.4), (0.0, 1.0)], 0.5)
    check()
    r2.teleport(Pose2D(-2.0, -1.0, 1.0))
    check()
    forward = r1.params.lidar.num_rays // 2
    r1.teleport(Pose2D(0.0, 0.0, 0.0))
    r3.teleport(Pose2D(1.5, 0.0, math.pi / 2))  # broadside, straight ahead of r1 now
    assert r1.lidar_scan().ranges_m[forward] == pytest.approx(1.35 - 0.10, abs=1e-6)


def test_robots_cannot_be_put_into_each_other(quiet: SimParams, open_world: Callable[..., World]) -> None:
    world = open_world()
    r1 = Robot(world, params=quiet, start=Pose2D(0.0, 0.0, 0.0), name="r1")
    with pytest.raises(PoseInCollisionError, match="robot 'r1'"):
        r1.join("r2", Pose2D(0.3, 0.0, 0.0))
    r2 = r1.join("r2", Pose2D(2.0, 0.0, 0.0))
    with pytest.raises(PoseInCollisionError, match="robot 'r2'"):
        r1.teleport(Pose2D(1.8, 0.1, 0.0))
    r1.teleport(Pose2D(-2.0, 0.0, 0.0))  # a fresh body: still in the room, still colliding with r2
    _drive_together([r1, r2], [(0.5, 0.0), (0.0, 0.0)], 10.0)
    assert [e.other_robot for e in r1.drain_collisions()] == ["r2"]
    with pytest.raises(ValueError, match="already in this room"):
        r1.join("r2", Pose2D(-4.0, 3.0, 0.0))


def test_a_shared_room_steps_only_together(quiet: SimParams, open_world: Callable[..., World]) -> None:
    world = open_world()
    r1 = Robot(world, params=quiet, start=Pose2D(0.0, 0.0, 0.0), name="r1")
    r1.step(0.1, 0.0)  # alone, it steps itself
    r2 = r1.join("r2", Pose2D(2.0, 2.0, 0.0))
    with pytest.raises(RuntimeError, match="step_together"):
        r1.step(0.1, 0.0)
    with pytest.raises(ValueError, match="every robot of one room"):
        step_together([r1], [(0.0, 0.0)])
    with pytest.raises(ValueError, match="commands"):
        step_together([r1, r2], [(0.0, 0.0)])
    step_together([r1, r2], [(0.0, 0.0), (0.2, 0.0)])
    assert r2.time_s == pytest.approx(r2.params.dt_s) and r1.steps == 2


def test_the_shipped_fleet_world_puts_every_robot_in_one_room(quiet: SimParams) -> None:
    from shared.world import load_world
    from tests.support.processes import REPO_ROOT

    world = load_world(REPO_ROOT / "deploy/worlds/fleet/warehouse.yaml")
    assert [r.name for r in world.robots] == ["r1", "r2", "r3"] and len(world.docks) == 2
    first, *rest = world.robots
    room = Robot(world, params=quiet, start=Pose2D.from_seq(first.start), name=first.name)
    robots = [room] + [room.join(r.name, Pose2D.from_seq(r.start)) for r in rest]
    assert [r.name for r in room.members] == ["r1", "r2", "r3"]
    _drive_together(robots, [(0.2, 0.0)] * 3, 1.0)
    assert all(not r.drain_collisions() for r in robots), "one second of driving from the starts hits nothing"


def test_the_camera_draws_the_other_robots(quiet: SimParams, open_world: Callable[..., World]) -> None:
    from services.simulator.camera import CameraParams, CameraRenderer, build_scene

    world = open_world()
    r1 = Robot(world, params=quiet, start=Pose2D(0.0, 0.0, 0.0), name="r1")
    r1.join("r2", Pose2D(1.0, 0.0, math.pi / 2))  # broadside, 1 m ahead
    camera = CameraRenderer(build_scene(world), CameraParams(noise_sigma=0.0))
    alone = camera.render(r1.pose).astype(float)
    seen = camera.render(r1.pose, others=r1.other_footprints()).astype(float)
    h, w = seen.shape
    # Below the horizon, in the middle of the image: the other robot's dark side where the floor was.
    patch = (slice(h // 2 + 5, h // 2 + 40), slice(w // 2 - 30, w // 2 + 30))
    assert seen[patch].mean() < alone[patch].mean() - 10.0
    edge = (slice(0, h), slice(0, 20))  # far to the side: nothing changes
    assert np.array_equal(seen[edge], alone[edge])
