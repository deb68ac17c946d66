"""Where a robot may be put down to start a docking: seeded, clear of every surface.

Beacon starts (in front of a dock, within its infrared beacon's reach) are shared by ``zendock trials``
and the infrared docking bench (:mod:`services.docking.ir_bench`), so that both draw from one
distribution.
"""

from __future__ import annotations

import math
import random

import numpy as np

from shared.geometry import Pose2D, distances_to_segment
from shared.world import ROBOT_FRONT_M, World

#: The robot's circumscribed radius plus a margin: starts this far from every surface can always turn.
START_CLEARANCE_M = 0.45

#: Beacon starts: this far from the dock's face (m) and this far off its axis, as infrared docking needs.
BEACON_DISTANCE_M = (0.7, 2.0)
BEACON_BEARING_RAD = math.radians(45.0)


def beacon_starts(world: World, n: int, seed: int) -> list[Pose2D]:
    """``n`` starts in front of the first dock, within its infrared beacon's reach, facing anywhere.

    Clear of every surface as :func:`random_starts`' are; every start sees the dock's face in a straight
    line, so each is connected to the dock without asking the planner.
    """
    rng = random.Random(seed)
    dock = world.docks[0].pose2d
    face = dock.compose(Pose2D(ROBOT_FRONT_M, 0.0, math.pi))  # x out of the dock
    segments = world.opaque_segments() + list(world.glass)
    starts: list[Pose2D] = []
    attempts = 0
    while len(starts) < n:
        attempts += 1
        if attempts > 200_000:
            raise RuntimeError(f"{world.name}: could not find {n} collision-free starts in front of the dock")
        distance = rng.uniform(*BEACON_DISTANCE_M)
        bearing = rng.uniform(-BEACON_BEARING_RAD, BEACON_BEARING_RAD)
        spot = face.compose(Pose2D(distance * math.cos(bearing), distance * math.sin(bearing), 0.0))
        if min(distance_to_segment((spot.x, spot.y), s) for s in segments) < START_CLEARANCE_M:
            continue
        if any(_crosses((spot.x, spot.y), (face.x, face.y), s) for s in world.opaque_segments()):
            continue  # a box or a wall between the start and the beacon
        starts.append(Pose2D(spot.x, spot.y, rng.uniform(-math.pi, math.pi)))
    return starts


def _crosses(a: tuple[float, float], b: tuple[float, float],
             segment: tuple[tuple[float, float], tuple[float, float]]) -> bool:
    """Whether the open segment a-b crosses ``segment`` (touching at b, the beacon on its own face, does not)."""
    (px, py), (qx, qy) = segment
    dx, dy, sx, sy = b[0] - a[0], b[1] - a[1], qx - px, qy - py
    denom = dx * sy - dy * sx
    if denom == 0.0:
        return False
    t = ((px - a[0]) * sy - (py - a[1]) * sx) / denom
    u = ((px - a[0]) * dy - (py - a[1]) * dx) / denom
    return 1e-6 < t < 1.0 - 1e-6 and 0.0 <= u <= 1.0


def distance_to_segment(p: tuple[float, float], segment: tuple[tuple[float, float], tuple[float, float]]) -> float:
    return float(distances_to_segment(np.array([p]), np.array(segment[0]), np.array(segment[1]))[0])
