"""Rasterising world files: what the lidar sees is in the map, glass is not, walls have no gaps."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pytest

from deploy.commands import map as map_command
from services.planner.occupancy_map import OCC_FREE, OCC_OCCUPIED, OCC_UNKNOWN, load_map
from services.planner.rasterize import map_from_world
from shared.world import DOCK_GEOMETRY, World, load_world, parse_world

WORLDS = Path(__file__).resolve().parents[3] / "deploy" / "worlds"


def _world(**fields: object) -> World:
    doc: dict = {"name": "test_room", "bounds": [0.0, 0.0, 4.0, 3.0], "robot": {"start": [0.5, 0.5, 0.0]}}
    doc.update(fields)
    return parse_world(doc)


def _eight_connected_reach(free: np.ndarray, seed: tuple[int, int]) -> np.ndarray:
    """Cells reachable from ``seed`` (row, col) through free cells, diagonal steps allowed."""
    reached = np.zeros_like(free)
    reached[seed] = True
    while True:
        grown = reached.copy()
        padded = np.pad(reached, 1)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                grown |= padded[1 + dy : 1 + dy + free.shape[0], 1 + dx : 1 + dx + free.shape[1]]
        grown &= free
        if np.array_equal(grown, reached):
            return reached
        reached = grown


def test_seed_room_has_walls_box_and_dock_but_free_floor() -> None:
    world = load_world(WORLDS / "seed_room.yaml")
    grid = map_from_world(world)
    assert grid.resolution_m == 0.05
    assert grid.origin == (-3.5, pytest.approx(-0.07), 0.0)
    # Outer walls: every cell along each edge of the bounds.
    for (x1, y1), (x2, y2) in world.boundary_walls():
        for t in np.linspace(0.0, 1.0, 50):
            assert grid.value_at(x1 + t * (x2 - x1), y1 + t * (y2 - y1)) == OCC_OCCUPIED
    # The inner wall, the box (filled, so its centre too) and the dock body.
    assert grid.value_at(2.0, 3.2) == OCC_OCCUPIED
    assert grid.value_at(-2.0, 3.8) == OCC_OCCUPIED
    body = DOCK_GEOMETRY.body_box(world.docks[0])
    assert grid.value_at(*body.pose[:2]) == OCC_OCCUPIED
    # Free where the robot drives, unknown outside the room.
    for x, y in [(0.0, 2.0), (-1.0, 1.4), world.robot.start[:2], (-1.0, 0.83)]:
        assert grid.value_at(x, y) == OCC_FREE
    assert grid.value_at(-3.3, 2.0) == OCC_UNKNOWN
    assert grid.value_at(0.0, 5.3) == OCC_UNKNOWN


def test_glass_is_not_in_the_map() -> None:
    world = load_world(WORLDS / "glass_room.yaml")
    grid = map_from_world(world)
    (gx1, gy), (gx2, _) = world.glass[0]
    for x in np.linspace(gx1 + 0.1, gx2 - 0.1, 30):
        assert grid.value_at(x, gy) == OCC_FREE
    (wx1, wy), (wx2, _) = world.walls[0]
    for x in np.linspace(wx1 + 0.1, wx2 - 0.1, 10):
        assert grid.value_at(x, wy) == OCC_OCCUPIED


@pytest.mark.parametrize(
    "wall",
    [
        [[0.0, 0.0], [4.0, 3.0]],  # shallow diagonal
        [[0.0, 0.0], [3.0, 3.0]],  # exactly 45 degrees through cell corners
        [[0.0, 3.0], [3.0, 0.0]],
        [[0.03, 0.0], [3.97, 2.95]],
    ],
)
def test_diagonal_walls_have_no_gaps(wall: list) -> None:
    grid = map_from_world(_world(walls=[wall]), resolution_m=0.1, padding_m=0.0)
    free = grid.data == OCC_FREE
    (x1, y1), (x2, y2) = wall
    # A free cell on each side of the wall, near its middle.
    mx, my = (x1 + x2) / 2, (y1 + y2) / 2
    nx, ny = -(y2 - y1), x2 - x1
    scale = 0.3 / math.hypot(nx, ny)
    left = grid.world_to_cell(mx + nx * scale, my + ny * scale)
    right = grid.world_to_cell(mx - nx * scale, my - ny * scale)
    assert free[left[1], left[0]] and free[right[1], right[0]]
    reach = _eight_connected_reach(free, (left[1], left[0]))
    assert not reach[right[1], right[0]], "free space leaks through the wall diagonally"


def test_rotated_box_is_filled_and_resolution_sets_grid_size() -> None:
    world = _world(boxes=[{"pose": [2.0, 1.5, math.pi / 5], "size": [1.0, 0.5]}])
    coarse = map_from_world(world, resolution_m=0.1, padding_m=0.5)
    fine = map_from_world(world, resolution_m=0.05, padding_m=0.5)
    assert (coarse.width, coarse.height) == (50, 40)
    assert (fine.width, fine.height) == (100, 80)
    for grid in (coarse, fine):
        for px, py in [(0.0, 0.0), (0.4, 0.2), (-0.4, -0.2), (0.3, -0.15)]:
            c, s = math.cos(math.pi / 5), math.sin(math.pi / 5)
            assert grid.value_at(2.0 + c * px - s * py, 1.5 + s * px + c * py) == OCC_OCCUPIED
        assert grid.value_at(2.0, 2.2) == OCC_FREE


def test_bad_resolution_or_padding() -> None:
    with pytest.raises(ValueError, match="resolution_m"):
        map_from_world(_world(), resolution_m=0.0)
    with pytest.raises(ValueError, match="padding_m"):
        map_from_world(_world(), padding_m=-1.0)


def _run_cli(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="zendock")
    map_command.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(argv)
    return args.func(args)


def test_map_save_command_writes_loadable_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "maps"
    code = _run_cli(
        ["map", "save", "--world", str(WORLDS / "seed_room.yaml"), "-o", str(out), "--resolution", "0.1"]
    )
    assert code == 0
    printed = capsys.readouterr().out.split()
    assert printed == [str(out / "seed_room.yaml"), str(out / "seed_room.pgm")]
    loaded = load_map(out / "seed_room.yaml")
    expected = map_from_world(load_world(WORLDS / "seed_room.yaml"), resolution_m=0.1)
    np.testing.assert_array_equal(loaded.data, expected.data)
    assert loaded.resolution_m == 0.1


def test_map_save_command_reports_a_bad_world(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: broken\nbounds: [0, 0, 1]\n")
    assert _run_cli(["map", "save", "--world", str(bad), "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "zendock map save:" in err and str(bad) in err and "bounds" in err
    assert not list(tmp_path.glob("*.pgm"))
    assert _run_cli(["map", "save", "--world", str(WORLDS / "seed_room.yaml"), "--resolution", "-1"]) == 2
    assert "--resolution" in capsys.readouterr().err
