"""Generated rooms on disk, each one reachable: ``zendock worlds generate`` and ``trials --world generated:KIND``.

:mod:`shared.world_gen` draws a room from a seed and checks what needs no planner; here each drawn room is
written out and the planner's own lower-bound tool (glass as solid as any wall) says whether the dock can
be reached from the room's start and from most of eight random starts. A room that fails is drawn again
(the next attempt of the same seed), so a seed always names the same kept room.
"""

from __future__ import annotations

import math
from pathlib import Path

import yaml

from deploy.trials.starts import lower_bounds
from shared.geometry import Pose2D
from shared.starts import random_starts
from shared.world import load_world
from shared.world_gen import generate_world, room_problems

#: Give up on a seed after this many drawn rooms (none has come close in 200 seeds of either kind).
MAX_ATTEMPTS = 20
#: Of the random starts checked, at least this share must reach the dock (trials draw their starts so).
REACHABLE_SHARE = 0.75


def generate_room(kind: str, seed: int, directory: Path) -> Path:
    """The room ``kind``/``seed`` as a world file in ``directory`` (written there), reachable."""
    directory.mkdir(parents=True, exist_ok=True)
    refused = []
    for attempt in range(MAX_ATTEMPTS):
        doc = generate_world(kind, seed, attempt)
        problems = room_problems(doc)
        if problems:
            refused.append(problems[0])
            continue
        path = directory / f"{doc['name']}.yaml"
        path.write_text(
            f"# zendock worlds generate --kind {kind} --seed {seed} (attempt {attempt})\n"
            + yaml.safe_dump(doc, sort_keys=False, default_flow_style=None),
            encoding="utf-8",
        )
        world = load_world(path)
        dock = world.docks[0].pose2d
        starts = [Pose2D(*world.robot.start), *random_starts(world, 8, seed)]
        bounds = lower_bounds(path, [(start, dock) for start in starts])
        reached = [math.isfinite(b) for b in bounds]
        if reached[0] and sum(reached[1:]) >= REACHABLE_SHARE * (len(reached) - 1):
            return path
        refused.append(f"the dock reached from {sum(reached)} of {len(reached)} starts")
        path.unlink()
    raise RuntimeError(f"no {kind} room kept for seed {seed} in {MAX_ATTEMPTS} attempts: {refused[-3:]}")


def generate_rooms(kind: str, first_seed: int, count: int, directory: Path) -> list[Path]:
    """``count`` rooms of ``kind``, seeds ``first_seed`` on, in ``directory``."""
    return [generate_room(kind, seed, directory) for seed in range(first_seed, first_seed + count)]
