"""Path lengths to the docks through the room's free space."""

from __future__ import annotations

import math

import pytest

from services.docking.room_paths import RoomPaths
from shared.geometry import Pose2D
from shared.world import load_world
from tests.support.processes import REPO_ROOT


def test_a_wall_between_makes_the_near_dock_the_far_one() -> None:
    # A 6 x 4 room split by a wall from (3, 0) to (3, 3.2): the way round is by the gap at the north.
    room = RoomPaths((0.0, 0.0, 6.0, 4.0), [((3.0, 0.0), (3.0, 3.2))])
    start = Pose2D(2.5, 0.5, 0.0)
    beyond, same_side = Pose2D(3.5, 0.5, 0.0), Pose2D(0.5, 0.5, 0.0)
    far, near = room.lengths(start, [beyond, same_side])
    assert near == pytest.approx(2.0, abs=0.15)
    assert far > 2 * (3.2 - 0.5) + 0.5, "round the wall's end"
    assert far < 8.0


def test_an_enclosed_goal_is_out_of_reach() -> None:
    box = [
        ((4.0, 1.0), (5.0, 1.0)),
        ((5.0, 1.0), (5.0, 2.0)),
        ((5.0, 2.0), (4.0, 2.0)),
        ((4.0, 2.0), (4.0, 1.0)),
    ]
    room = RoomPaths((0.0, 0.0, 6.0, 4.0), box)
    assert room.lengths(Pose2D(1.0, 1.0, 0.0), [Pose2D(4.5, 1.5, 0.0)]) == [math.inf]


def test_in_the_warehouse_the_dock_down_the_near_aisle_is_nearer() -> None:
    world = load_world(REPO_ROOT / "deploy/worlds/fleet/warehouse.yaml")
    room = RoomPaths(world.bounds, [*world.opaque_segments(), *world.glass])
    west, east = room.lengths(Pose2D(4.0, 4.0, 0.0), [Pose2D(1.5, 1.3, 0.0), Pose2D(10.5, 1.3, 0.0)])
    assert west < east and math.isfinite(east)
