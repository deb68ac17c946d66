"""How close a robot's footprint came to the world's glass: a trial's near misses, not only its contacts.

A glass campaign counts collisions, but they are rare events: runs of the same code over the same 100 rooms
gave 0 to 6, so one run cannot tell a change that halves the risk from one that does nothing. How close the
robot passed the panes is measured on every trial, touched or not, and a pass within a few centimetres is
the same mechanism as a touch (an unheard pane end grazed at speed), only luckier. Counting those gives a
figure that moves with the risk and that one campaign can compare.

Measured on ground truth (the observer's 20 Hz track) against the world file's panes, with the simulator's
footprint: a ``ROBOT_LENGTH_M`` x ``ROBOT_WIDTH_M`` rectangle centred on base_link, panes of no thickness.
Each pane is sampled every :data:`PANE_SAMPLE_M`, so the figure is good to a few millimetres; between two
track samples (2.5 cm apart at 0.5 m/s) the closest moment may fall, so it reads up to about a centimetre
wide. Touches are counted by the simulator, not here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from shared.world import ROBOT_LENGTH_M, ROBOT_WIDTH_M, World

#: Pane points are taken this far apart along each pane.
PANE_SAMPLE_M = 0.005
#: A trial whose footprint came this close to a pane passed it by a hair: a near miss (a touch included).
NEAR_GLASS_M = 0.05
#: Clearances are measured up to this; a trial that never came closer reads it (1 m or more).
CLEARANCE_CAP_M = 1.0


@dataclass(frozen=True, slots=True)
class GlassPass:
    """The closest a footprint came to glass: the gap (m, 0 when it touched) and the pane point nearest."""

    clearance_m: float
    x: float
    y: float


def pane_points(world: World, spacing_m: float = PANE_SAMPLE_M) -> np.ndarray:
    """``(N, 2)`` points along every pane of ``world``, at most ``spacing_m`` apart, both ends included."""
    chunks = []
    for (ax, ay), (bx, by) in world.glass:
        n = max(1, math.ceil(math.hypot(bx - ax, by - ay) / spacing_m))
        t = np.linspace(0.0, 1.0, n + 1)[:, None]
        chunks.append(np.array([ax, ay]) + t * np.array([bx - ax, by - ay]))
    return np.concatenate(chunks) if chunks else np.zeros((0, 2))


def closest_glass_pass(
    world: World,
    track: Sequence[tuple[float, float, float, float]],
    length_m: float = ROBOT_LENGTH_M,
    width_m: float = ROBOT_WIDTH_M,
) -> GlassPass | None:
    """The closest the footprint came to a pane along ``track`` (``(t, x, y, yaw)`` ground-truth samples),
    at most :data:`CLEARANCE_CAP_M` (then with no point); None when the world has no glass or the track is
    empty."""
    points = pane_points(world)
    if len(points) == 0 or len(track) == 0:
        return None
    poses = np.asarray(track, dtype=float).reshape(-1, 4)[:, 1:]
    half_l, half_w = 0.5 * length_m, 0.5 * width_m
    # Only pane points this close to a sample's centre can lie within the cap of its footprint.
    reach = math.hypot(half_l, half_w) + CLEARANCE_CAP_M
    best = GlassPass(CLEARANCE_CAP_M, math.nan, math.nan)
    lo, hi = poses[:, :2].min(axis=0) - reach, poses[:, :2].max(axis=0) + reach
    near = points[np.all((points >= lo) & (points <= hi), axis=1)]
    for x, y, yaw in poses if len(near) else ():
        close = near[((near[:, 0] - x) ** 2 + (near[:, 1] - y) ** 2) <= reach * reach]
        if not len(close):
            continue
        dx, dy = close[:, 0] - x, close[:, 1] - y
        c, s = math.cos(yaw), math.sin(yaw)
        # each pane point in the body frame, then its distance to the rectangle (0 inside it)
        bx = np.abs(c * dx + s * dy) - half_l
        by = np.abs(-s * dx + c * dy) - half_w
        gaps = np.hypot(np.maximum(bx, 0.0), np.maximum(by, 0.0))
        i = int(np.argmin(gaps))
        if gaps[i] < best.clearance_m:
            best = GlassPass(float(gaps[i]), float(close[i, 0]), float(close[i, 1]))
    return best


__all__ = ["CLEARANCE_CAP_M", "NEAR_GLASS_M", "GlassPass", "closest_glass_pass", "pane_points"]
