"""The dock's infrared beacon as the robot's three receivers see it (Kobuki's fields and bits)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from shared.geometry import Pose2D
from shared.models.infrared import (
    FAR_CENTER,
    FAR_LEFT,
    FAR_RIGHT,
    NEAR_CENTER,
    NEAR_LEFT,
    InfraredParams,
    fields_at,
    receiver_readings,
)
from shared.models.raycast import SegmentSet
from shared.world import ROBOT_FRONT_M, World

QUIET = InfraredParams(dropout=0.0)


def _read(world: World, robot: Pose2D, params: InfraredParams = QUIET) -> tuple[int, int, int]:
    return receiver_readings(
        robot, world.docks, SegmentSet(world.opaque_segments()), params, np.random.default_rng(0)
    )


def test_fields_split_the_front_of_the_dock_into_centre_sides_near_and_far() -> None:
    assert fields_at(1.0, 0.0, QUIET) == FAR_CENTER
    assert fields_at(0.4, 0.0, QUIET) == FAR_CENTER | NEAR_CENTER
    assert fields_at(1.0, 0.5, QUIET) == FAR_LEFT
    assert fields_at(0.4, 0.2, QUIET) == FAR_LEFT | NEAR_LEFT
    assert fields_at(1.0, -0.5, QUIET) == FAR_RIGHT
    assert (
        fields_at(1.0, 0.05, QUIET) == FAR_CENTER | FAR_LEFT
    )  # just off the axis: both, as on the real dock
    assert fields_at(-0.5, 0.0, QUIET) == 0  # behind the face
    assert fields_at(3.0, 0.0, QUIET) == 0  # out of reach


def test_the_central_receiver_sees_the_centre_only_when_facing_the_dock(
    dock_world: Callable[..., World],
) -> None:
    world = dock_world()  # dock at the origin facing +x: the docked robot stands at the origin
    in_front = Pose2D(-1.0 + ROBOT_FRONT_M, 0.0, 0.0)
    right, central, left = _read(world, in_front)
    assert central == FAR_CENTER and right == 0 and left == 0
    assert _read(world, Pose2D(in_front.x, in_front.y, math.pi))[1] == 0  # facing away
    assert _read(world, Pose2D(-0.3 + ROBOT_FRONT_M, 0.0, 0.0))[1] == FAR_CENTER | NEAR_CENTER


def test_a_side_receiver_sees_the_dock_beside_the_robot(dock_world: Callable[..., World]) -> None:
    world = dock_world()
    # The dock faces -x (its face towards the robot): +y is the dock's own right. Heading across the axis
    # (-y), the robot has the dock on its left: the left receiver sees the right field.
    right, central, left = _read(world, Pose2D(-0.8, 0.6, -math.pi / 2))
    assert left & FAR_RIGHT and central == 0 and right == 0
    right, central, left = _read(world, Pose2D(-0.8, -0.6, math.pi / 2))
    assert right & FAR_LEFT and central == 0 and left == 0


def test_walls_block_the_beacon_and_glass_does_not(dock_world: Callable[..., World]) -> None:
    robot = Pose2D(-1.2, 0.0, 0.0)
    walled = dock_world(walls=[[[-0.6, -0.5], [-0.6, 0.5]]])
    glazed = dock_world(glass=[[[-0.6, -0.5], [-0.6, 0.5]]])
    assert _read(walled, robot) == (0, 0, 0)
    assert _read(glazed, robot)[1] == FAR_CENTER


def test_readings_flicker_at_the_dropout_rate(dock_world: Callable[..., World]) -> None:
    world = dock_world()
    rng = np.random.default_rng(1)
    params = InfraredParams(dropout=0.2)
    segments = SegmentSet(world.opaque_segments())
    seen = [
        receiver_readings(Pose2D(-0.8, 0.0, 0.0), world.docks, segments, params, rng)[1] for _ in range(2000)
    ]
    lost = sum(1 for bits in seen if not bits & FAR_CENTER) / len(seen)
    assert 0.15 < lost < 0.25
