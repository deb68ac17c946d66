"""The world a fleet run uses: the given world with exactly N robots, each with patrol waypoints.

A fleet world lists its robots (``robots: [{name, start, patrol}]``). A run may ask for fewer (the first
N) or more (the others placed at seeded, collision-free starts, reachable from the first robot's); a
robot without patrol waypoints gets some: seeded spots clear of every surface, away from the docks and
the holding poses, each reachable by the planner's own tool, spread over the room. The result is
written next to the run's report, so the run can be repeated and read exactly as it ran.
"""

from __future__ import annotations

import math
import random
from pathlib import Path
from typing import Any

import yaml

from deploy.trials.starts import lower_bounds, random_starts
from shared.config_errors import ConfigError, read_yaml_file
from shared.geometry import Pose2D
from shared.structs import plain
from shared.world import World, load_world, parse_world

#: Patrol waypoints generated per robot.
PATROL_WAYPOINTS = 4
#: Generated starts and waypoints keep this far from other robots' starts and from holding poses.
KEEP_APART_M = 1.0
#: Generated waypoints keep this far from every dock, out of its approach.
PATROL_DOCK_CLEARANCE_M = 1.8


def fleet_world(world_path: Path, robots: int | None, seed: int, out: Path) -> tuple[World, Path]:
    """The effective world (``robots`` of them, all with patrols), validated and written to ``out``."""
    data: dict[str, Any] = read_yaml_file(world_path, "world file")
    world = parse_world(data, world_path)
    if not world.docks:
        raise ConfigError(f"{world_path}: a fleet needs docks to share, and this world has none")
    listed = [plain(r) for r in world.robots] or [{"name": "r1", "start": list(world.robot.start)}]
    n = len(listed) if robots is None else robots
    rng = random.Random(seed)
    chosen = listed[:n]
    if n > len(chosen):
        chosen += _extra_robots(world_path, world, chosen, n - len(chosen), rng)
    for i, robot in enumerate(chosen):
        if not robot.get("patrol"):
            robot["patrol"] = [
                list(p.as_tuple())
                for p in _patrol(world_path, world, Pose2D.from_seq(robot["start"]), seed + 101 * (i + 1))
            ]
        robot["start"] = [float(v) for v in robot["start"]]
        robot["patrol"] = [[float(v) for v in p] for p in robot["patrol"]]
    effective = {**data, "robots": chosen}
    effective.pop("robot", None)
    out.write_text(yaml.safe_dump(effective, sort_keys=False))
    return load_world(out), out


def _extra_robots(
    world_path: Path, world: World, placed: list[dict[str, Any]], count: int, rng: random.Random
) -> list[dict[str, Any]]:
    taken = {r["name"] for r in placed}
    names = (f"r{i}" for i in range(1, 10_000) if f"r{i}" not in taken)
    avoid = [tuple(r["start"][:2]) for r in placed] + [tuple(h[:2]) for h in world.holding]
    candidates = [
        c
        for c in random_starts(world, 40 * count + 20, rng.randrange(1 << 30))
        if all(math.dist((c.x, c.y), a) >= KEEP_APART_M for a in avoid)
    ]
    reachable = _reachable_from(
        world_path, Pose2D.from_seq(placed[0]["start"]) if placed else None, candidates
    )
    extra: list[dict[str, Any]] = []
    for spot in reachable:
        if len(extra) == count:
            break
        if all(math.dist((spot.x, spot.y), a) >= KEEP_APART_M for a in avoid):
            extra.append({"name": next(names), "start": list(spot.as_tuple())})
            avoid.append((spot.x, spot.y))
    if len(extra) < count:
        raise ConfigError(f"{world_path}: found room for only {len(extra)} of {count} more robots")
    return extra


def _patrol(world_path: Path, world: World, start: Pose2D, seed: int) -> list[Pose2D]:
    avoid = [tuple(h[:2]) for h in world.holding]
    candidates = [
        c
        for c in random_starts(world, 30, seed)
        if all(math.dist((c.x, c.y), a) >= KEEP_APART_M for a in avoid)
        and all(math.dist((c.x, c.y), d.pose[:2]) >= PATROL_DOCK_CLEARANCE_M for d in world.docks)
    ]
    reachable = _reachable_from(world_path, start, candidates)
    if len(reachable) < 2:
        raise ConfigError(
            f"{world_path}: found only {len(reachable)} reachable patrol spots for a robot at "
            f"{[round(start.x, 2), round(start.y, 2)]}"
        )
    # Spread over the room: each next waypoint the reachable spot farthest from those chosen.
    chosen = [max(reachable, key=lambda c: math.dist((c.x, c.y), (start.x, start.y)))]
    while len(chosen) < min(PATROL_WAYPOINTS, len(reachable)):
        chosen.append(max(reachable, key=lambda c: min(math.dist((c.x, c.y), (p.x, p.y)) for p in chosen)))
    return chosen


def _reachable_from(world_path: Path, start: Pose2D | None, spots: list[Pose2D]) -> list[Pose2D]:
    if start is None:
        return spots
    bounds = lower_bounds(world_path, [(start, spot) for spot in spots])
    return [spot for spot, bound in zip(spots, bounds) if math.isfinite(bound)]
