import math
from pathlib import Path

import pytest

from services.docking.dock_db import DockDatabase, load_dock_db, parse_dock_db
from services.docking.errors import DockingError, DockingErrorCode
from shared.config_errors import ConfigError
from shared.geometry import Pose2D
from shared.world import load_world

SEED_ROOM_WORLD = Path(__file__).resolve().parents[3] / "deploy" / "worlds" / "seed_room.yaml"
TWO_DOCKS = {
    "docks": [
        {"id": "home", "pose": [-1.0, 0.83, -math.pi / 2], "type": "charger"},
        {"id": "lab", "pose": [3.0, 2.0, 0.0], "type": "pallet"},
    ]
}


def test_world_file_is_a_dock_database() -> None:
    db = load_dock_db(SEED_ROOM_WORLD)
    assert db.ids == ["home"]
    assert db.get("home").pose2d == Pose2D(-1.0, 0.83, -math.pi / 2)
    world = load_world(SEED_ROOM_WORLD)
    assert DockDatabase.from_world(world).ids == ["home"]


def test_dock_file_loads(tmp_path: Path) -> None:
    path = tmp_path / "docks.yaml"
    path.write_text(
        "docks:\n  - {id: a, pose: [1.0, 2.0, 0.5], type: charger}\n  - {id: b, pose: [0, 0, 0]}\n"
    )
    db = load_dock_db(path)
    assert len(db) == 2 and "a" in db and "c" not in db
    assert db.get("b").type == "charger"
    assert [d.id for d in db] == ["a", "b"]


def test_unknown_id_is_dock_not_in_db() -> None:
    db = parse_dock_db(TWO_DOCKS, "docks.yaml")
    with pytest.raises(DockingError) as info:
        db.get("kitchen")
    assert info.value.error_code == DockingErrorCode.DOCK_NOT_IN_DB
    assert "kitchen" in str(info.value) and "home" in str(info.value)


def test_choose_by_id_or_nearest() -> None:
    db = parse_dock_db(TWO_DOCKS)
    assert db.choose("lab").id == "lab"
    assert db.choose(robot_pose=Pose2D(2.0, 2.0, 0.0)).id == "lab"
    assert db.choose(robot_pose=Pose2D(0.0, 0.0, 0.0)).id == "home"
    assert db.nearest(Pose2D(2.5, 2.0, 0.0), dock_type="charger").id == "home"
    for no_dock in (lambda: db.nearest(Pose2D(), dock_type="conveyor"), db.choose):
        with pytest.raises(DockingError) as info:
            no_dock()
        assert info.value.error_code == DockingErrorCode.DOCK_NOT_VALID
    single = parse_dock_db({"docks": TWO_DOCKS["docks"][:1]})
    assert single.choose().id == "home"


@pytest.mark.parametrize(
    ("document", "expected"),
    [
        ([1, 2], "must be a mapping"),
        ({"name": "room"}, "docks: missing"),
        ({"docks": {"id": "a"}}, "docks: must be a list"),
        ({"docks": []}, "docks: the list is empty"),
        ({"docks": ["home"]}, "docks.0: must be a mapping"),
        ({"docks": [{"pose": [0, 0, 0]}]}, "docks.0.id"),
        ({"docks": [{"id": "a", "pose": [0, 0]}]}, "docks.0.pose"),
        ({"docks": [{"id": "a", "pose": [0, "x", 0]}]}, "docks.0.pose.1"),
        ({"docks": [{"id": "a", "pose": [0, float("nan"), 0]}]}, "docks.0.pose: must be finite"),
        (
            {"docks": [{"id": "a", "pose": [0, 0, 0]}, {"id": "a", "pose": [1, 0, 0]}]},
            "docks.1.id: dock id 'a' appears twice",
        ),
    ],
)
def test_malformed_input_names_file_and_field(document: object, expected: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_dock_db(document, "docks.yaml")
    assert str(info.value).startswith("docks.yaml: ")
    assert expected in str(info.value)


def test_unreadable_and_invalid_yaml_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read dock database"):
        load_dock_db(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("docks: [\n")
    with pytest.raises(ConfigError, match="bad.yaml: not valid YAML"):
        load_dock_db(bad)
