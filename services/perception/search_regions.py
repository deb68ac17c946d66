"""Where to look for markers in the next frame: around where they were, with a whole-frame search often enough.

ArUco's detector thresholds and traces contours over every pixel it is given, so most of a frame's cost is
the empty wall around a marker. A marker found in one frame is near the same place in the next (at 15
frames a second the robot turns at most 0.1 rad between them, about 55 pixels at the default focal
length), so the next frame is searched only in a box around each marker's last corners, widened by
the marker's own size and at least ``MIN_MARGIN_PX``. The whole frame is searched

- when no marker was seen in the last ``MEMORY_S`` (image stamps),
- every ``FULL_SEARCH_EVERY`` frames, so that a marker coming into view is found within that many,
- and again on the same frame whenever a box misses its marker: a lost marker costs no detection.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from services.perception.markers import MarkerSighting

MIN_MARGIN_PX = 64
MEMORY_S = 0.5
FULL_SEARCH_EVERY = 8

Box = tuple[int, int, int, int]


class SearchRegions:
    """The boxes to search in the next frame, from the markers found in the last one."""

    def __init__(
        self,
        min_margin_px: int = MIN_MARGIN_PX,
        memory_s: float = MEMORY_S,
        full_search_every: int = FULL_SEARCH_EVERY,
    ) -> None:
        self.min_margin_px = min_margin_px
        self.memory_s = memory_s
        self.full_search_every = full_search_every
        self._last: dict[int, np.ndarray] = {}
        self._last_stamp_s: float | None = None
        self._since_full = 0

    def boxes(self, stamp_s: float, width: int, height: int) -> list[Box] | None:
        """Boxes to search in a frame of this size and stamp; None: search the whole frame."""
        fresh = self._last_stamp_s is not None and 0.0 <= stamp_s - self._last_stamp_s <= self.memory_s
        if not self._last or not fresh or self._since_full + 1 >= self.full_search_every:
            return None
        boxes = []
        for corners in self._last.values():
            lo, hi = corners.min(axis=0), corners.max(axis=0)
            margin = max(float(np.max(hi - lo)), float(self.min_margin_px))
            x0, y0 = (int(max(0.0, np.floor(v - margin))) for v in lo)
            x1, y1 = (
                int(min(width, np.ceil(hi[0] + margin) + 1)),
                int(min(height, np.ceil(hi[1] + margin) + 1)),
            )
            if x1 > x0 and y1 > y0:
                boxes.append((x0, y0, x1, y1))
        return boxes or None

    def complete(self, sightings: Sequence[MarkerSighting]) -> bool:
        """Whether a search of the boxes found every marker they were drawn around."""
        return set(self._last) <= {s.marker_id for s in sightings}

    def update(self, sightings: Sequence[MarkerSighting], stamp_s: float, whole_frame: bool) -> None:
        """What a search of the frame stamped ``stamp_s`` found."""
        self._since_full = 0 if whole_frame else self._since_full + 1
        if sightings:
            self._last = {s.marker_id: s.corners for s in sightings}
            self._last_stamp_s = stamp_s
        elif whole_frame:
            self._last = {}
