"""A probabilistic model of one sonar reading: how much each cell of its cone is occupied or free.

A sonar echo says "the nearest surface somewhere in this cone is at ``r``", not "the whole arc at ``r``
is occupied". Marking the whole arc puts false glass in front of an oblique pane: the nearest echo comes
from the cone's edge, and the rest of the arc, up to ``0.5 r sin(incidence)`` in front of the pane, is
marked too. This model follows Nav2's RangeSensorLayer (after Thrun et al., *Probabilistic Robotics*,
ch. 6, and the sonar model of Elfes, 1989): each reading adds log-odds evidence per cell,

- occupied evidence in the band ``|d - r| <= band`` around the echo's range, strongest on the beam's axis
  and falling off with the angle from it (``1 - (theta / half_fov)^n``), in the band's outer half, and
  with the echo's range past ``trusted_range_m`` (Nav2's ``phi_v``: ``1 - (1 + tanh(2 (r - phi_v))) / 2``):
  a far echo's arc is wide (``fov * r``), and one echo says little about which of its cells made it;
- free evidence inside the measured range (the sonar looked through those cells), also weighted by angle,
  but only for cells the cone covers whole: a cell half inside the cone may hold a pane's end in its other
  half (see :func:`reading_evidence`);
- nothing beyond the echo (the sonar cannot see behind what it heard).

Evidence accumulates (log-odds, clamped so that the map can change its mind), and cells are marked or
cleared by thresholds, so a pane's extent converges as the robot looks from several poses, and cells
seen through are cleared. One more rule, where this model goes past Nav2's: an echo is explained by
one surface, so the arc cells already known to be free (seen through from elsewhere) get no occupied
evidence from it, and the rest of the arc gets it as if it were the whole arc: the echo came from there.
At an oblique pane the first looks mark cells in front of it, later looks see through them, and the
echoes that follow are pinned on the pane itself even when it lies at the cone's edge. Which part of the
arc an echo may have come from is also told by the echoes before it (:mod:`services.planner.echo_pairing`);
the glass memory passes that on as ``candidates`` too.

Pure numpy: no grid, no bus. :mod:`services.planner.glass_memory` applies it to the glass memory.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def log_odds(probability: float) -> float:
    return math.log(probability / (1.0 - probability))


@dataclass(frozen=True, slots=True)
class RangeSensorModel:
    """The model's probabilities and thresholds (a single reading's, on the beam's axis)."""

    #: P(occupied) of a cell on the axis at the echo's range, from one near reading (``trusted_range_m``
    #: weakens far ones): one echo marks the middle three quarters of the arc (glass must stop the robot
    #: the first time it is heard near).
    hit_probability: float = 0.95
    #: P(occupied) of a cell on the axis the beam passed through: one clear look undoes one echo.
    miss_probability: float = 0.1
    #: Half width of the band round the echo's range that the echo may come from (at least a cell).
    range_band_m: float = 0.05
    #: A cell is glass at or above this probability (Nav2's default is 0.8; 0.7 keeps one echo's mark as
    #: wide as the part of the arc it is likely to come from) ...
    mark_threshold: float = 0.7
    #: ... and known to be free at or below this one.
    clear_threshold: float = 0.3
    #: Log-odds are clamped to +-this: evidence never so sure that new readings cannot overturn it.
    max_log_odds: float = 4.0
    #: The range at which an echo's occupied evidence has fallen to half (Nav2's ``phi_v``; its default is
    #: 1.2 m, which left far glass unmarked until the robot came near). One echo from 1.5 m still marks (0.88
    #: of a near one's evidence), one from 2.5 m gives an eighth and one from 3 m a fiftieth. An echo's arc is
    #: ``fov * r`` wide and the surface that made it lies on one cell of it: at 3 m the arc is 1.5 m, and an
    #: oblique pane or a pane's end put up to 0.75 m of it in front of the glass, out on the floor. Glass
    #: heard from afar is still held for ``echo_hold_s`` (see :mod:`services.planner.glass_memory`), and
    #: echoes that agree from look to look still add up.
    trusted_range_m: float = 2.0
    #: The share of its occupied evidence an echo gives its arc while no other echo can tell where on the
    #: arc it came from (:mod:`services.planner.echo_pairing`); the rest follows, where the two agree, once
    #: one can. A near echo still marks on its own: glass heard close ahead must stop the robot.
    unplaced_echo_share: float = 0.5

    def __post_init__(self) -> None:
        for name in ("hit_probability", "miss_probability", "mark_threshold", "clear_threshold"):
            value = getattr(self, name)
            if not (0.0 < value < 1.0):
                raise ValueError(f"RangeSensorModel.{name} must lie strictly between 0 and 1, got {value!r}")
        if not (self.miss_probability < 0.5 < self.hit_probability):
            raise ValueError("RangeSensorModel needs miss_probability < 0.5 < hit_probability")
        if not (self.clear_threshold < 0.5 < self.mark_threshold):
            raise ValueError("RangeSensorModel needs clear_threshold < 0.5 < mark_threshold")
        if not (self.range_band_m > 0.0 and self.max_log_odds > 0.0):
            raise ValueError("RangeSensorModel.range_band_m and max_log_odds must be positive")
        if not (0.0 < self.unplaced_echo_share <= 1.0):
            raise ValueError(
                f"RangeSensorModel.unplaced_echo_share must lie in (0, 1], got {self.unplaced_echo_share!r}"
            )
        if not (math.isfinite(self.trusted_range_m) and self.trusted_range_m > 0.0):
            raise ValueError(
                f"RangeSensorModel.trusted_range_m must be positive, got {self.trusted_range_m!r}"
            )

    @property
    def mark_log_odds(self) -> float:
        return log_odds(self.mark_threshold)

    @property
    def clear_log_odds(self) -> float:
        return log_odds(self.clear_threshold)


#: The angular falloff's exponent: ``1 - (theta / half_fov)^n``. Nav2 uses 2; a flatter top (8) lets one
#: echo mark 90 % of the arc's width, as a pane straight ahead fills it, so a pane's end is marked the first
#: time it is heard (with 2, the robot once reached the end of a pane before its flank was marked); the
#: falloff still leaves the cone's very edge, where oblique echoes come from, to accumulated evidence.
ANGULAR_FALLOFF_EXPONENT = 8


def angular_weight(bearing_rad: np.ndarray, half_fov_rad: float) -> np.ndarray:
    """How much a reading says about a cell at ``bearing_rad`` off the axis: 1 on it, 0 at the cone's edge."""
    ratio = np.abs(np.asarray(bearing_rad, dtype=float)) / half_fov_rad
    return np.where(ratio < 1.0, 1.0 - ratio**ANGULAR_FALLOFF_EXPONENT, 0.0)


def range_weight(range_m: float, trusted_range_m: float) -> float:
    """How much one echo from ``range_m`` says about the cells of its arc (Nav2's ``delta(phi)``): near 1
    well inside ``trusted_range_m``, one half at it, near 0 beyond twice it."""
    return 1.0 - 0.5 * (1.0 + math.tanh(2.0 * (range_m - trusted_range_m)))


def reading_evidence(
    distance_m: np.ndarray,
    bearing_rad: np.ndarray,
    range_m: float,
    half_fov_rad: float,
    echo: bool,
    model: RangeSensorModel,
    band_m: float | None = None,
    candidates: np.ndarray | None = None,
    cell_reach_m: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Log-odds evidence of one reading for cells at ``distance_m`` and ``bearing_rad`` from the sensor.

    Returns ``(free, occupied)``: per cell, the (negative) free evidence of the cone the beam passed
    through and the (positive) occupied evidence of the echo's band. With ``echo`` False (no echo out to
    ``range_m``, the maximum range) there is only free evidence. Cells outside the cone get neither.

    ``candidates`` (boolean per cell) says which cells may have made the echo; the others (known to be
    free) get no occupied evidence, and the angular weights of the band's candidates are scaled so that
    the strongest is 1: when the part of the arc nearest the axis is known to be free, the echo came
    from the rest, however far off the axis.

    ``cell_reach_m``: how far any point of a cell may lie from its centre (half its diagonal, plus the
    sensor pose's uncertainty). Only a cell that lies whole inside the cone and short of the echo was
    seen through: the nearest surface in the cone is at the echo's range, so such a cell holds none. A
    cell the cone covers only in part gets no free evidence, for glass may stand in its other part. This
    is what keeps a pane's end from becoming "known free": the cone's edge sweeps past the end's cell
    look after look, and with its centre inside the cone it would pile up free evidence and, known free,
    never be credited with an echo again (a robot hit pane ends that way late in a long campaign:
    measurement 20).
    """
    distance = np.asarray(distance_m, dtype=float)
    bearing = np.abs(np.asarray(bearing_rad, dtype=float))
    weight = angular_weight(bearing, half_fov_rad)
    band = model.range_band_m if band_m is None else max(band_m, model.range_band_m)
    free_limit = range_m - band if echo else range_m
    seen_through = distance + cell_reach_m < free_limit
    if cell_reach_m > 0.0:
        # The cell's angular half width seen from the sensor; a cell round the sensor itself is not whole in the cone.
        half_width = np.arcsin(np.clip(cell_reach_m / np.maximum(distance, 1e-9), 0.0, 1.0))
        seen_through &= (distance > cell_reach_m) & (bearing + half_width < half_fov_rad)
    free = np.where(seen_through, weight * log_odds(model.miss_probability), 0.0)
    if not echo:
        return free, np.zeros_like(free)
    # Full weight within half the band (a cell's centre is up to half a cell off the arc), none past it.
    off = np.abs(distance - range_m) / band
    across = np.clip(2.0 * (1.0 - off), 0.0, 1.0)
    in_band = off <= 1.0
    if candidates is not None:
        candidates = np.asarray(candidates, dtype=bool)
        in_band &= candidates
        strongest = float(weight[in_band].max()) if in_band.any() else 0.0
        if strongest > 0.0:
            weight = np.minimum(weight / strongest, 1.0)
    hit = 0.5 + (model.hit_probability - 0.5) * weight * across * range_weight(range_m, model.trusted_range_m)
    occupied = np.where(in_band, np.log(hit / (1.0 - hit)), 0.0)
    return free, occupied
