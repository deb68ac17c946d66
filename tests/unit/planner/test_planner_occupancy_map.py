"""Occupancy maps: cell conversions and the map_server YAML + PGM format (P5 and P2, negate, errors)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from services.planner.occupancy_map import (
    OCC_FREE,
    OCC_OCCUPIED,
    OCC_UNKNOWN,
    OccupancyMap,
    load_map,
    read_pgm,
    save_map,
)
from shared.config_errors import ConfigError


def _write_yaml(path: Path, **fields: object) -> Path:
    doc = {
        "image": "map.pgm",
        "resolution": 0.1,
        "origin": [1.0, -2.0, 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    doc.update(fields)
    lines = [f"{key}: {value}" for key, value in doc.items() if value is not None]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_world_and_cell_conversions_are_inverse_and_follow_ros_layout() -> None:
    grid = OccupancyMap(resolution_m=0.05, origin=(-1.0, 2.0, 0.0), data=np.zeros((30, 40)))
    assert (grid.width, grid.height) == (40, 30)
    assert grid.world_to_cell(-1.0 + 0.001, 2.0 + 0.001) == (0, 0)
    assert grid.world_to_cell(-1.0 + 0.05 * 7.5, 2.0 + 0.05 * 3.2) == (7, 3)
    assert grid.cell_to_world(7, 3) == pytest.approx((-1.0 + 0.375, 2.0 + 0.175))
    assert not grid.in_bounds(*grid.world_to_cell(-1.01, 2.5))
    grid.data[3, 7] = OCC_OCCUPIED
    assert grid.value_at(*grid.cell_to_world(7, 3)) == OCC_OCCUPIED
    assert grid.value_at(100.0, 100.0) == OCC_UNKNOWN


def test_rotated_origin_is_honoured() -> None:
    grid = OccupancyMap(resolution_m=0.1, origin=(1.0, 1.0, math.pi / 2), data=np.zeros((10, 10)))
    # The grid's x axis points along world +y: cell (2, 0) lies above the origin.
    x, y = grid.cell_to_world(2, 0)
    assert (x, y) == pytest.approx((1.0 - 0.05, 1.0 + 0.25))
    assert grid.world_to_cell(x, y) == (2, 0)


def test_rejects_values_outside_occupancy_range() -> None:
    with pytest.raises(ValueError, match="occupancy values"):
        OccupancyMap(resolution_m=0.05, origin=(0, 0, 0), data=np.full((2, 2), 101))


def test_save_and_load_round_trip(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    data = rng.choice(np.array([OCC_UNKNOWN, OCC_FREE, OCC_OCCUPIED], dtype=np.int8), size=(23, 37))
    original = OccupancyMap(resolution_m=0.05, origin=(-3.5, -0.07, 0.0), data=data)
    yaml_path, pgm_path = save_map(original, tmp_path / "room.yaml")
    assert pgm_path == tmp_path / "room.pgm" and pgm_path.read_bytes().startswith(b"P5")
    loaded = load_map(yaml_path)
    assert loaded.resolution_m == 0.05
    assert loaded.origin == (-3.5, -0.07, 0.0)
    np.testing.assert_array_equal(loaded.data, original.data)


def test_saved_image_is_upside_down_with_map_saver_shades(tmp_path: Path) -> None:
    data = np.zeros((3, 2), dtype=np.int8)
    data[0, 0] = OCC_OCCUPIED  # bottom-left of the map
    data[2, 1] = OCC_UNKNOWN  # top-right
    _, pgm_path = save_map(OccupancyMap(0.1, (0, 0, 0), data), tmp_path / "m.yaml")
    pixels, maxval = read_pgm(pgm_path)
    assert maxval == 255
    np.testing.assert_array_equal(pixels, [[254, 205], [254, 254], [0, 254]])


def test_loads_hand_written_ascii_pgm_with_comments(tmp_path: Path) -> None:
    # Row 0 of the image is the top of the map. maxval 15: p = (15 - v) / 15.
    (tmp_path / "map.pgm").write_text(
        "P2\n# drawn by hand\n3 2\n# maxval next\n15\n"
        "0 15 8\n"  # top row: occupied (p=1), free (p=0), unknown (p=0.47)
        "15 3 12\n"  # bottom row: free, occupied (p=0.8), p=0.2 -> unknown (not below 0.196)
    )
    loaded = load_map(_write_yaml(tmp_path / "map.yaml"))
    assert (loaded.width, loaded.height) == (3, 2)
    np.testing.assert_array_equal(
        loaded.data, [[OCC_FREE, OCC_OCCUPIED, OCC_UNKNOWN], [OCC_OCCUPIED, OCC_FREE, OCC_UNKNOWN]]
    )
    assert loaded.origin == (1.0, -2.0, 0.0) and loaded.resolution_m == 0.1


def test_negate_swaps_black_and_white(tmp_path: Path) -> None:
    (tmp_path / "map.pgm").write_text("P2 2 1 255 0 255\n")
    plain = load_map(_write_yaml(tmp_path / "plain.yaml"))
    negated = load_map(_write_yaml(tmp_path / "negated.yaml", negate=1))
    np.testing.assert_array_equal(plain.data, [[OCC_OCCUPIED, OCC_FREE]])
    np.testing.assert_array_equal(negated.data, [[OCC_FREE, OCC_OCCUPIED]])


def test_thresholds_follow_map_server(tmp_path: Path) -> None:
    # p = (255 - v) / 255: v=89 -> 0.651 (occupied), v=90 -> 0.647 (unknown), v=205 -> 0.196 (unknown),
    # v=206 -> 0.192 (free).
    (tmp_path / "map.pgm").write_bytes(b"P5\n4 1\n255\n" + bytes([89, 90, 205, 206]))
    loaded = load_map(_write_yaml(tmp_path / "map.yaml"))
    np.testing.assert_array_equal(loaded.data, [[OCC_OCCUPIED, OCC_UNKNOWN, OCC_UNKNOWN, OCC_FREE]])


def test_sixteen_bit_binary_pgm(tmp_path: Path) -> None:
    (tmp_path / "map.pgm").write_bytes(
        b"P5 2 1 65535\n" + (0).to_bytes(2, "big") + (65535).to_bytes(2, "big")
    )
    loaded = load_map(_write_yaml(tmp_path / "map.yaml"))
    np.testing.assert_array_equal(loaded.data, [[OCC_OCCUPIED, OCC_FREE]])


def test_scale_mode_keeps_intermediate_values(tmp_path: Path) -> None:
    (tmp_path / "map.pgm").write_bytes(b"P5\n1 1\n255\n" + bytes([128]))  # p = 0.498
    loaded = load_map(_write_yaml(tmp_path / "map.yaml", mode="scale", free_thresh=0.25))
    assert loaded.data[0, 0] == round((0.498039 - 0.25) / (0.65 - 0.25) * 100)


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"resolution": -0.05}, "resolution"),
        ({"origin": "[0, 0]"}, "origin"),
        ({"occupied_thresh": None}, "occupied_thresh"),
        ({"free_thresh": 1.5}, "free_thresh"),
        ({"free_thresh": 0.9}, "must not exceed occupied_thresh"),
        ({"mode": "colour"}, "mode"),
        ({"negate": 3}, "negate"),
    ],
)
def test_bad_fields_name_file_and_field(tmp_path: Path, fields: dict, message: str) -> None:
    (tmp_path / "map.pgm").write_bytes(b"P5\n1 1\n255\n\x00")
    yaml_path = _write_yaml(tmp_path / "map.yaml", **fields)
    with pytest.raises(ConfigError, match=message) as err:
        load_map(yaml_path)
    assert str(yaml_path) in str(err.value)


def test_missing_image_is_reported(tmp_path: Path) -> None:
    yaml_path = _write_yaml(tmp_path / "map.yaml", image="nowhere.pgm")
    with pytest.raises(ConfigError, match=r"image: no such file .*nowhere\.pgm") as err:
        load_map(yaml_path)
    assert str(yaml_path) in str(err.value)


def test_malformed_yaml_and_non_mapping(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("image: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_map(bad)
    bad.write_text("- just\n- a list\n")
    with pytest.raises(ConfigError, match="must be a mapping"):
        load_map(bad)
    with pytest.raises(ConfigError, match="cannot read map file"):
        load_map(tmp_path / "absent.yaml")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"P6\n1 1\n255\n\x00\x00\x00", "not a PGM"),
        (b"P5\n2 2\n255\n\x00", "short"),
        (b"P2\n2 1\n255\n0\n", "has 1 pixels"),
        (b"P2\n1 1\n10\n11\n", "above maxval"),
        (b"P5\n1\n", "header ends early"),
    ],
)
def test_bad_images_are_reported(tmp_path: Path, content: bytes, message: str) -> None:
    (tmp_path / "map.pgm").write_bytes(content)
    with pytest.raises(ConfigError, match=message) as err:
        load_map(_write_yaml(tmp_path / "map.yaml"))
    assert "map.pgm" in str(err.value)
