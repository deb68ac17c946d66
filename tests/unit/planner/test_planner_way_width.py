"""The widest way's narrowest gap: a door's width, a pane that narrows it, no way at all."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from services.planner.shortest_path import solid_map
from services.planner.way_width import MAX_CLEARANCE_M, WayWidths, way_widths
from shared.structs import plain
from shared.world import World, parse_world

REPO_ROOT = Path(__file__).resolve().parents[3]
START, GOAL = (1.0, 2.0), (5.0, 2.0)


def _two_rooms(door_m: float, door_from_y: float = 1.5, glass: list[Any] | None = None) -> World:
    """Two rooms side by side, 6 x 4 m, a partition at x = 3 with a door ``door_m`` wide."""
    walls = [[[3.0, 0.0], [3.0, door_from_y]], [[3.0, door_from_y + door_m], [3.0, 4.0]]]
    doc = {
        "name": "two rooms",
        "bounds": [0.0, 0.0, 6.0, 4.0],
        "walls": [w for w in walls if abs(w[1][1] - w[0][1]) > 1e-6],
        "glass": glass or [],
        "docks": [{"id": "home", "pose": [5.6, 2.0, 0.0]}],
        "robot": {"start": [1.0, 2.0, 0.0]},
    }
    return parse_world(doc, "two rooms")


@pytest.mark.parametrize("door_m", [0.4, 0.5, 0.63, 0.8, 1.2])
@pytest.mark.parametrize("door_from_y", [1.5, 1.52, 1.537])
def test_a_doors_width_is_found_within_a_cell(door_m: float, door_from_y: float) -> None:
    (width,) = way_widths(solid_map(_two_rooms(door_m, door_from_y)), GOAL, [START])
    assert width == pytest.approx(door_m, abs=0.05)


def test_a_pane_in_front_of_the_door_narrows_the_way_to_what_it_leaves() -> None:
    # A pane 0.1 m before a 1 m door covers its lower 0.6 m: the way left passes between the pane's top
    # end (2.9, 2.1) and the wall's end (3.0, 2.5), 0.41 m apart.
    pane = [[[2.9, 1.5], [2.9, 2.1]]]
    open_door = way_widths(solid_map(_two_rooms(1.0)), GOAL, [START])[0]
    narrowed = way_widths(solid_map(_two_rooms(1.0, glass=pane)), GOAL, [START])[0]
    assert open_door == pytest.approx(1.0, abs=0.05)
    assert narrowed == pytest.approx(0.41, abs=0.05)


def test_no_way_is_width_zero_and_an_open_room_is_capped() -> None:
    closed = _two_rooms(0.0)
    assert way_widths(solid_map(closed), GOAL, [START]) == [0.0]
    open_room = parse_world(
        {"name": "hall", "bounds": [0.0, 0.0, 12.0, 12.0], "robot": {"start": [1.0, 1.0, 0.0]}}, "hall"
    )
    widths = WayWidths(solid_map(open_room), (9.0, 9.0))
    assert widths.width_m((3.0, 3.0)) == pytest.approx(2 * MAX_CLEARANCE_M)
    # a start within the goal's free play is as open as can be
    assert widths.width_m((9.2, 9.0)) == pytest.approx(2 * MAX_CLEARANCE_M)


def test_the_lower_bound_tool_answers_each_start_with_its_way_width(tmp_path: Path) -> None:
    world = tmp_path / "two_rooms.yaml"
    doc = plain(_two_rooms(0.8))
    world.write_text(yaml.safe_dump(doc), encoding="utf-8")
    queries = [
        {"start": [1.0, 2.0, 0.0], "goal": [5.0, 2.0, 0.0]},  # through the door
        {"start": [4.5, 3.0, 0.0], "goal": [5.0, 2.0, 0.0]},  # in the goal's room
    ]
    done = subprocess.run(
        [sys.executable, "-m", "services.planner.lower_bound", "--world", str(world), "--batch"],
        input="\n".join(json.dumps(q) for q in queries),
        capture_output=True,
        text=True,
        cwd=REPO_ROOT,
        timeout=60,
        check=True,
    )
    through, inside = (json.loads(line) for line in done.stdout.splitlines())
    assert through["way_width_m"] == pytest.approx(0.8, abs=0.05)
    assert inside["way_width_m"] > 1.5
