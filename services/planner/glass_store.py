"""Glass memory that outlives the planner process.

What the sonar found is the one part of the planner's picture no map holds: a planner restarted in the
middle of a run (a crash, ``kill -9``, an upgrade) would otherwise drive into the panes it had already
found, sonar-blind round their ends, until it found them again. The sonar layer is written to a file
(atomically: a temporary file, then a rename) whenever it changed, at most every ``period`` seconds, and
read back at start-up -- only onto the same grid and the same static map, so a file left by another
world or another map is ignored rather than trusted.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from services.planner.occupancy_map import OccupancyMap
from shared.files import write_atomically


def map_fingerprint(occupancy: OccupancyMap) -> str:
    """Identifies a static map: its grid geometry and its cells."""
    import hashlib  # noqa: PLC0415 - only a planner given a glass_memory_file hashes its map

    frame = occupancy.frame
    digest = hashlib.sha256(np.ascontiguousarray(occupancy.data).tobytes())
    digest.update(repr((frame.width, frame.height, frame.resolution_m, tuple(frame.origin))).encode())
    return digest.hexdigest()


class GlassStore:
    """Reads and writes one sonar layer for one static map."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._saved: np.ndarray | None = None
        self._fingerprint: tuple[OccupancyMap, str] | None = None

    def _fingerprint_of(self, occupancy: OccupancyMap) -> str:
        """The map's fingerprint, hashed once per map rather than at every save."""
        if self._fingerprint is None or self._fingerprint[0] is not occupancy:
            self._fingerprint = (occupancy, map_fingerprint(occupancy))
        return self._fingerprint[1]

    def load(self, occupancy: OccupancyMap) -> np.ndarray | None:
        """The stored layer when it was made on this very map; None when absent, foreign or unreadable."""
        try:
            with np.load(self.path, allow_pickle=False) as stored:
                fingerprint = str(stored["map"])
                layer = np.array(stored["sonar"], dtype=np.uint8)
        except (OSError, KeyError, ValueError):
            return None
        if fingerprint != self._fingerprint_of(occupancy) or layer.shape != occupancy.data.shape:
            return None
        self._saved = layer.copy()
        return layer

    def save_if_changed(self, occupancy: OccupancyMap, layer: np.ndarray) -> bool:
        """Write ``layer`` unless it equals what was last written; True when written."""
        if self._saved is not None and np.array_equal(layer, self._saved):
            return False
        buffer = io.BytesIO()
        frame = occupancy.frame
        # The grid's geometry travels with the layer, so tools can place its cells without the map.
        np.savez(
            buffer,
            map=np.array(self._fingerprint_of(occupancy)),
            sonar=layer,
            resolution=np.array(frame.resolution_m),
            origin=np.array(frame.origin, dtype=float),
        )
        write_atomically(self.path, buffer.getvalue())
        self._saved = layer.copy()
        return True
