"""The infrared docking bench closes the service's own task with the simulator's beacon in a world file."""

from __future__ import annotations

import math

from services.docking.ir_bench import Room, dock_from
from shared.geometry import Pose2D
from shared.starts import beacon_starts
from shared.world import parse_world

ROOM = parse_world(
    {
        "name": "ir",
        "bounds": [-3, -3, 3, 3],
        "docks": [{"id": "home", "pose": [2.4, 0, 0]}],
        "boxes": [{"pose": [0.0, 1.5, 0.0], "size": [0.5, 0.5]}],
        "robot": {"start": [0, 0, 0]},
    }
)


def test_from_beacon_starts_the_task_docks_on_its_contacts_without_touching_anything_else() -> None:
    room = Room(ROOM)
    for i, start in enumerate(beacon_starts(ROOM, 3, seed=4)):
        trial = dock_from(room, start, seed=i)
        assert trial.docked, (start, trial.outcome, trial.states)
        assert trial.collisions == 0 and trial.lateral_error_m <= 0.04 and trial.yaw_error_rad <= 0.1


def test_a_wall_just_ahead_is_solid_and_blocks_the_way() -> None:
    room = Room(ROOM)
    facing_wall = Pose2D(-2.75, 0.0, math.pi)  # front 5 cm from the west wall: any drive forward touches it
    assert not room.overlaps(facing_wall, room.solid)
    assert room.overlaps(Pose2D(-2.85, 0.0, math.pi), room.solid)
    assert room.blocked(facing_wall, 1.0) and not room.blocked(Pose2D(0.0, 0.0, 0.0), 1.0)


def test_a_run_that_gives_up_says_where_the_drive_was_and_what_it_tried() -> None:
    room = Room(ROOM)
    trial = dock_from(room, beacon_starts(ROOM, 1, seed=4)[0], seed=0, max_time_s=3.0)
    assert not trial.docked
    assert (
        trial.outcome.startswith("not charging after 3 s (in ") and "states begun: scan 1x" in trial.outcome
    )
