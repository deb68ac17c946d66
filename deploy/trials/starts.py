"""Where trials start: seeded, collision-free, and connected to the dock (by the planner's own tool)."""

from __future__ import annotations

import json
import math
import random
from pathlib import Path

import numpy as np

from deploy.service_tools import run_tool
from shared.geometry import Pose2D, distances_to_segment
from shared.world import ROBOT_FRONT_M, World

#: The robot's circumscribed radius plus a margin: starts this far from every surface can always turn.
START_CLEARANCE_M = 0.45
#: Starts at least this far from the dock, so each trial navigates before it docks.
MIN_START_DISTANCE_TO_DOCK_M = 1.2


def random_starts(world: World, n: int, seed: int) -> list[Pose2D]:
    """``n`` start poses with clearance from every surface (glass included) and away from the docks."""
    rng = random.Random(seed)
    xmin, ymin, xmax, ymax = world.bounds
    segments = world.opaque_segments() + list(world.glass)
    starts: list[Pose2D] = []
    attempts = 0
    while len(starts) < n:
        attempts += 1
        if attempts > 200_000:
            raise RuntimeError(f"{world.name}: could not find {n} collision-free starts")
        x, y = rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)
        if min(_distance_to_segment((x, y), s) for s in segments) < START_CLEARANCE_M:
            continue
        if any(math.dist((x, y), d.pose[:2]) < MIN_START_DISTANCE_TO_DOCK_M for d in world.docks):
            continue
        starts.append(Pose2D(x, y, rng.uniform(-math.pi, math.pi)))
    return starts


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
        if min(_distance_to_segment((spot.x, spot.y), s) for s in segments) < START_CLEARANCE_M:
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


def reachable_starts(world_path: Path, world: World, n: int, seed: int) -> list[Pose2D]:
    """The first ``n`` of :func:`random_starts` from which the dock can be reached at all.

    A world may hold closed pockets (behind the walls of ``corridor``): a start there tests nothing but
    the harness. Reachability comes from the planner's own lower-bound tool (glass counted as solid);
    a start it cannot connect to the dock is skipped, so the other starts stay what the seed made them.
    """
    candidates = random_starts(world, 2 * n + 10, seed)
    dock = world.docks[0].pose2d
    bounds = lower_bounds(world_path, [(start, dock) for start in candidates])
    starts = [start for start, bound in zip(candidates, bounds) if math.isfinite(bound)][:n]
    if len(starts) < n:
        raise RuntimeError(f"{world.name}: only {len(starts)} of {len(candidates)} random starts can reach the dock")
    return starts


def _distance_to_segment(p: tuple[float, float], segment: tuple[tuple[float, float], tuple[float, float]]) -> float:
    return float(distances_to_segment(np.array([p]), np.array(segment[0]), np.array(segment[1]))[0])


def lower_bounds(world_path: Path, pairs: list[tuple[Pose2D, Pose2D]]) -> list[float]:
    """Shortest collision-free times for ``(start, goal)`` pairs, from the planner's own tool (one process);
    NaN where a pair is not connected."""
    if not pairs:
        return []
    lines = "\n".join(json.dumps({"start": list(s.as_tuple()), "goal": list(g.as_tuple())}) for s, g in pairs)
    done = run_tool("services.planner.lower_bound", ["--world", str(world_path), "--batch"], input_text=lines)
    if done.returncode != 0:
        raise RuntimeError(f"lower bounds failed: {done.stderr.strip()[-300:]}")
    bounds = [json.loads(line).get("lower_bound_s") for line in done.stdout.strip().splitlines()]
    return [math.nan if bound is None else float(bound) for bound in bounds]
