"""Where trials start: seeded, collision-free, and connected to the dock (by the planner's own tool)."""

from __future__ import annotations

import json
import math
from pathlib import Path

from deploy.service_tools import run_tool
from shared.geometry import Pose2D
from shared.starts import (  # noqa: F401 - the trials' starts
    BEACON_BEARING_RAD,
    BEACON_DISTANCE_M,
    START_CLEARANCE_M,
    beacon_starts,
    distance_to_segment,
    random_starts,
)
from shared.world import World


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
        raise RuntimeError(
            f"{world.name}: only {len(starts)} of {len(candidates)} random starts can reach the dock"
        )
    return starts


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
