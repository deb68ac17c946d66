"""Where trials start: seeded, collision-free, and connected to the dock (by the planner's own tool)."""

from __future__ import annotations

import json
import math
from pathlib import Path

from deploy.service_tools import run_tool
from deploy.trials.time_over_bound import BOUND_MAX_ANGULAR_RADPS, BOUND_MAX_LINEAR_MPS, LowerBound
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
    return [bound.seconds for bound in lower_bound_parts(world_path, pairs)]


def lower_bound_parts(world_path: Path, pairs: list[tuple[Pose2D, Pose2D]]) -> list[LowerBound]:
    """:func:`lower_bounds` with what each is made of (path length, turns); NaN where not connected."""
    if not pairs:
        return []
    lines = "\n".join(json.dumps({"start": list(s.as_tuple()), "goal": list(g.as_tuple())}) for s, g in pairs)
    speeds = ["--max-linear", str(BOUND_MAX_LINEAR_MPS), "--max-angular", str(BOUND_MAX_ANGULAR_RADPS)]
    done = run_tool(
        "services.planner.lower_bound", ["--world", str(world_path), "--batch", *speeds], input_text=lines
    )
    if done.returncode != 0:
        raise RuntimeError(f"lower bounds failed: {done.stderr.strip()[-300:]}")
    return [_bound(json.loads(line)) for line in done.stdout.strip().splitlines()]


def _bound(answer: dict[str, float | None]) -> LowerBound:
    def number(key: str) -> float:
        value = answer.get(key)
        return math.nan if value is None else float(value)

    return LowerBound(
        number("lower_bound_s"), number("path_length_m"), number("turn_rad"), number("way_width_m")
    )
