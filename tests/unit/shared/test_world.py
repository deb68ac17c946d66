"""World files: the shipped worlds load, the tutorial's dock is where it should be, bad files say why."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from shared.config_errors import ConfigError
from shared.world import DOCK_GEOMETRY, ROBOT_FRONT_M, load_world, parse_world

WORLDS_DIR = Path(__file__).resolve().parents[3] / "deploy" / "worlds"
WORLDS = sorted(WORLDS_DIR.rglob("*.yaml"))

VALID = {
    "name": "t",
    "bounds": [0, 0, 4, 3],
    "walls": [[[1, 0], [1, 1]]],
    "glass": [[[2, 0], [2, 1]]],
    "boxes": [{"pose": [3, 2, 0.3], "size": [0.4, 0.2]}],
    "docks": [{"id": "home", "pose": [0.5, 2.0, math.pi / 2]}],
    "robot": {"start": [2, 2, 0]},
}


@pytest.mark.parametrize("path", WORLDS, ids=lambda p: str(p.relative_to(WORLDS_DIR)))
def test_shipped_worlds_load(path: Path) -> None:
    world = load_world(path)
    assert world.docks, "every shipped world has a dock"


def test_seed_room_reproduces_the_tutorial_dock() -> None:
    world = load_world(WORLDS_DIR / "seed_room.yaml")
    dock = world.dock("home")
    assert dock.pose[:2] == (-1.0, 0.83) and dock.pose[2] == pytest.approx(-math.pi / 2)


def test_dock_body_stands_ahead_of_the_dock_pose() -> None:
    world = parse_world(VALID)
    body = DOCK_GEOMETRY.body_box(world.docks[0])
    # dock faces +y: the body starts at the robot's front and extends further along +y
    ys = [c[1] for c in body.corners()]
    assert min(ys) == pytest.approx(2.0 + ROBOT_FRONT_M)
    assert len(world.opaque_segments()) == 4 + 1 + 4 + 4  # bounds, wall, box, dock body; glass is not opaque


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ({"bounds": [0, 0, -1, 3]}, "bounds: xmax > xmin"),
        ({"bounds": [0, 0, 1]}, "bounds"),
        ({"walls": [[[1, 1], [1, 1]]]}, "zero length"),
        ({"walls": [[[1, 1]]]}, "walls.0"),
        ({"boxes": [{"pose": [1, 1, 0], "size": [0, 1]}]}, "boxes.0.size"),
        ({"docks": [{"id": "a", "pose": [1, 1, 0]}, {"id": "a", "pose": [2, 1, 0]}]}, "appears twice"),
        ({"docks": [{"id": "a", "pose": [10, 1, 0]}]}, "outside bounds"),
        ({"docks": [{"pose": [1, 1, 0]}]}, "docks.0.id"),
        ({"robot": {"start": [1, "x", 0]}}, "robot.start.1"),
        ({"name": ""}, "name"),
        ({"glass": [[[0, 0], [float("nan"), 1]]]}, "finite"),
    ],
)
def test_malformed_worlds_name_the_problem(change: dict, expected: str) -> None:
    data = VALID | change
    with pytest.raises(ConfigError) as info:
        parse_world(data, "bad.yaml")
    text = str(info.value)
    assert text.startswith("bad.yaml: ")
    for part in expected.split(": "):
        assert part in text


def test_missing_required_key() -> None:
    data = {k: v for k, v in VALID.items() if k != "bounds"}
    with pytest.raises(ConfigError, match=r"w.yaml: bounds: missing \(required\)"):
        parse_world(data, "w.yaml")


@pytest.mark.parametrize(
    ("change", "where"),
    [
        ({"wals": [[[1, 0], [1, 1]]]}, "wals"),
        ({"docks": [{"id": "d", "pose": [1, 1, 0], "color": "red"}]}, "docks.0.color"),
        ({"boxes": [{"pose": [3, 2, 0], "size": [1, 1], "height": 2}]}, "boxes.0.height"),
        ({"robots": [{"name": "r1", "start": [1, 1, 0], "strat": [1, 1, 0]}]}, "robots.0.strat"),
    ],
)
def test_unknown_keys_are_errors_naming_the_key_and_the_file(change: dict, where: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_world(VALID | change, "w.yaml")
    assert str(info.value).startswith(f"w.yaml: {where}: unknown key")


def test_a_misspelt_robot_key_is_named_not_the_default_it_leaves() -> None:
    with pytest.raises(ConfigError) as info:
        parse_world(VALID | {"robot": {"strat": [2, 2, 0]}}, "w.yaml")
    assert str(info.value) == "w.yaml: robot.strat: unknown key (did you mean start?)"


def test_unreadable_and_non_yaml_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read"):
        load_world(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_world(bad)
    bad.write_text("- a list\n")
    with pytest.raises(ConfigError, match="must be a mapping"):
        load_world(bad)
