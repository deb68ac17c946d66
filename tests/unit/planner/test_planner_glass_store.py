"""The glass memory's file: written when changed, read back only onto the map it was made on."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from services.planner.costmap import LETHAL_OBSTACLE, NO_INFORMATION
from services.planner.glass_store import GlassStore
from services.planner.occupancy_map import OCC_FREE, OCC_OCCUPIED, OccupancyMap


def _map(wall_at: int = 5) -> OccupancyMap:
    data = np.full((20, 30), OCC_FREE, dtype=np.int8)
    data[:, wall_at] = OCC_OCCUPIED
    return OccupancyMap(0.05, (0.0, 0.0, 0.0), data)


def test_a_layer_comes_back_on_the_same_map_and_is_written_only_when_changed(tmp_path: Path) -> None:
    occupancy = _map()
    layer = np.full((20, 30), NO_INFORMATION, dtype=np.uint8)
    layer[10, 12:18] = LETHAL_OBSTACLE
    path = tmp_path / "r0" / "glass.npz"
    store = GlassStore(path)
    assert store.save_if_changed(occupancy, layer)
    assert not store.save_if_changed(occupancy, layer.copy())
    restored = GlassStore(path).load(_map())
    assert restored is not None and np.array_equal(restored, layer)
    assert not list(path.parent.glob(".*.tmp"))  # the temporary file was renamed into place


def test_a_file_from_another_map_or_a_damaged_one_is_ignored(tmp_path: Path) -> None:
    path = tmp_path / "glass.npz"
    GlassStore(path).save_if_changed(_map(wall_at=5), np.zeros((20, 30), dtype=np.uint8))
    assert GlassStore(path).load(_map(wall_at=6)) is None
    path.write_bytes(b"not a numpy archive")
    assert GlassStore(path).load(_map(wall_at=5)) is None
    assert GlassStore(tmp_path / "missing.npz").load(_map()) is None
