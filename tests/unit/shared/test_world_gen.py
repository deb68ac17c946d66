"""Generated rooms: the same seed gives the same room, every kept room parses and leaves the dock's approach
clear, and glass rooms are glass-heavy, halls among them."""

from __future__ import annotations

import argparse
import math

import pytest

from deploy.world_names import campaign_world
from shared.world import parse_world
from shared.world_gen import APPROACH_CLEAR_M, KINDS, generate_world, room_problems


def _kept(kind: str, seed: int) -> dict:
    for attempt in range(20):
        doc = generate_world(kind, seed, attempt)
        if not room_problems(doc):
            return doc
    raise AssertionError(f"{kind} seed {seed}: no room kept in 20 attempts")


@pytest.mark.parametrize("kind", KINDS)
def test_every_seed_gives_a_room_that_is_kept_and_the_same_room_again(kind: str) -> None:
    for seed in range(60):
        doc = _kept(kind, seed)
        assert doc == _kept(kind, seed)
        world = parse_world(doc, doc["name"])
        assert doc["name"].startswith(f"generated-{kind}-{seed}")
        assert len(world.docks) == 1 and world.placement_problem(*world.robot.start[:2]) is None


def test_glass_rooms_have_glass_and_some_are_halls_ordinary_rooms_none() -> None:
    glass = [_kept("glass", seed) for seed in range(60)]
    rooms = [_kept("room", seed) for seed in range(60)]
    assert all(len(doc["glass"]) >= 2 for doc in glass)
    assert all(not doc["glass"] for doc in rooms)
    halls = [doc for doc in glass if doc["bounds"][2] >= 16.0 and doc["bounds"][3] >= 12.0]
    assert 5 <= len(halls) <= 30, len(halls)
    assert len({tuple(doc["bounds"]) for doc in glass}) == len(glass)  # every room its own


def test_a_pane_in_front_of_the_dock_is_refused() -> None:
    doc = _kept("glass", 7)
    x, y, yaw = doc["docks"][0]["pose"]
    behind = (x - 0.5 * APPROACH_CLEAR_M * math.cos(yaw), y - 0.5 * APPROACH_CLEAR_M * math.sin(yaw))
    across = [[behind[0] - 0.3 * math.sin(yaw), behind[1] + 0.3 * math.cos(yaw)], [behind[0], behind[1]]]
    problems = room_problems({**doc, "glass": [*doc["glass"], across]})
    assert any("stands in the approach to the dock" in p for p in problems), problems


def test_an_unknown_kind_is_refused_naming_the_kinds() -> None:
    with pytest.raises(ValueError, match="kinds: room, glass"):
        generate_world("hall", 1)
    with pytest.raises(argparse.ArgumentTypeError, match="KIND one of: room, glass"):
        campaign_world("generated:hall")
    assert campaign_world("generated:glass") == "generated:glass"
