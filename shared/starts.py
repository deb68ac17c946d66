"""Where a robot may be put down to start a docking: seeded, clear of every surface.

Room starts and beacon starts (in front of a dock, within its infrared beacon's reach) are shared by
``zendock trials``, ``zendock fleet`` and the infrared docking bench (:mod:`services.docking.ir_bench`),
so that they all draw from one distribution.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable

import numpy as np

from shared.geometry import Pose2D, distances_to_segment
from shared.world import ROBOT_FRONT_M, Segment, World

#: The robot's circumscribed radius plus a margin: starts this far from every surface can always turn.
START_CLEARANCE_M = 0.45

#: Beacon starts: this far from the dock's face (m) and this far off its axis, as infrared docking needs.
BEACON_DISTANCE_M = (0.7, 2.0)
BEACON_BEARING_RAD = math.radians(45.0)


#: Starts at least this far from the dock, so each trial navigates before it docks.
MIN_START_DISTANCE_TO_DOCK_M = 1.2
#: Draws a sampler makes before it gives up on a world.
MAX_DRAWS = 200_000


def _draw(n: int, draw: Callable[[], Pose2D | None], failure: str) -> list[Pose2D]:
    """``n`` poses from ``draw`` (None: that draw is rejected); ``RuntimeError(failure)`` after too many draws."""
    starts: list[Pose2D] = []
    for _ in range(MAX_DRAWS):
        if len(starts) == n:
            return starts
        pose = draw()
        if pose is not None:
            starts.append(pose)
    if len(starts) == n:
        return starts
    raise RuntimeError(failure)


def _clear(segments: list[Segment], x: float, y: float) -> bool:
    return min(distance_to_segment((x, y), s) for s in segments) >= START_CLEARANCE_M


def random_starts(world: World, n: int, seed: int) -> list[Pose2D]:
    """``n`` start poses with clearance from every surface (glass included) and away from the docks."""
    rng = random.Random(seed)
    xmin, ymin, xmax, ymax = world.bounds
    segments = world.opaque_segments() + list(world.glass)

    def draw() -> Pose2D | None:
        x, y = rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)
        if not _clear(segments, x, y):
            return None
        if any(math.dist((x, y), d.pose[:2]) < MIN_START_DISTANCE_TO_DOCK_M for d in world.docks):
            return None
        return Pose2D(x, y, rng.uniform(-math.pi, math.pi))

    return _draw(n, draw, f"{world.name}: could not find {n} collision-free starts")


def beacon_starts(world: World, n: int, seed: int) -> list[Pose2D]:
    """``n`` starts in front of the first dock, within its infrared beacon's reach, facing anywhere.

    Clear of every surface as :func:`random_starts`' are; every start sees the dock's face in a straight
    line, so each is connected to the dock without asking the planner.
    """
    rng = random.Random(seed)
    dock = world.docks[0].pose2d
    face = dock.compose(Pose2D(ROBOT_FRONT_M, 0.0, math.pi))  # x out of the dock
    opaque = world.opaque_segments()
    segments = opaque + list(world.glass)

    def draw() -> Pose2D | None:
        distance = rng.uniform(*BEACON_DISTANCE_M)
        bearing = rng.uniform(-BEACON_BEARING_RAD, BEACON_BEARING_RAD)
        spot = face.compose(Pose2D(distance * math.cos(bearing), distance * math.sin(bearing), 0.0))
        if not _clear(segments, spot.x, spot.y):
            return None
        if any(_crosses((spot.x, spot.y), (face.x, face.y), s) for s in opaque):
            return None  # a box or a wall between the start and the beacon
        return Pose2D(spot.x, spot.y, rng.uniform(-math.pi, math.pi))

    return _draw(n, draw, f"{world.name}: could not find {n} collision-free starts in front of the dock")


def _crosses(
    a: tuple[float, float], b: tuple[float, float], segment: tuple[tuple[float, float], tuple[float, float]]
) -> bool:
    """Whether the open segment a-b crosses ``segment`` (touching at b, the beacon on its own face, does not)."""
    (px, py), (qx, qy) = segment
    dx, dy, sx, sy = b[0] - a[0], b[1] - a[1], qx - px, qy - py
    denom = dx * sy - dy * sx
    if denom == 0.0:
        return False
    t = ((px - a[0]) * sy - (py - a[1]) * sx) / denom
    u = ((px - a[0]) * dy - (py - a[1]) * dx) / denom
    return 1e-6 < t < 1.0 - 1e-6 and 0.0 <= u <= 1.0


def distance_to_segment(
    p: tuple[float, float], segment: tuple[tuple[float, float], tuple[float, float]]
) -> float:
    return float(distances_to_segment(np.array([p]), np.array(segment[0]), np.array(segment[1]))[0])
