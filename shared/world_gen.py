"""Rooms nobody tuned for: world documents made from a seed, for campaigns over hundreds of rooms.

:func:`generate_world` draws one room of a kind from a seed: its size, an inner partition with a door,
boxes, glass panes at any angle, and a dock on any wall facing into the room. Kinds:

- ``room``: an ordinary room, 5-10 m by 4-8 m, a partition now and then, boxes, no glass;
- ``glass``: glass-heavy rooms of every size up to halls of 18 x 13 m: panes at any angle, panes beside
  the dock (an alcove of glass), a glass partition with a door, long panes in big halls.

A drawn room is kept only if it passes the checks that need no planner (:func:`room_problems`): the
approach to the dock is clear for 1.3 m in front of it, the robot's start has room, every pane and box is
inside the bounds. Whether the dock can be reached is the planner's to say (``zendock worlds generate``
asks its lower-bound tool, and draws again on the next attempt when it cannot). The same kind, seed and
attempt always give the same room; its ``name`` says all three, so any trial can be made again.
"""

from __future__ import annotations

import math
import random
from typing import Any

import numpy as np

from shared.geometry import Pose2D
from shared.starts import START_CLEARANCE_M, distance_to_segment
from shared.world import DOCK_GEOMETRY, ROBOT_FRONT_M, ROBOT_WIDTH_M, World, parse_world

KINDS = ("room", "glass")
#: In front of the dock this far (along its axis) and this wide nothing may stand: the approach's corridor.
APPROACH_CLEAR_M = 1.3
APPROACH_HALF_WIDTH_M = ROBOT_WIDTH_M / 2.0 + 0.2
#: From the dock pose to the wall its body stands against.
DOCK_BACK_M = ROBOT_FRONT_M + DOCK_GEOMETRY.body_depth_m
#: The robot starts at least this far from the dock, so every trial has a way to drive.
START_AWAY_M = 1.5
#: Panes and boxes keep this far from the outer walls (a gap a robot could not use is no gap).
EDGE_MARGIN_M = 0.05


def world_name(kind: str, seed: int, attempt: int = 0) -> str:
    return f"generated-{kind}-{seed}" + (f"-{attempt}" if attempt else "")


def generate_world(kind: str, seed: int, attempt: int = 0) -> dict[str, Any]:
    """One room of ``kind`` drawn from ``seed`` (``attempt``: the next draw when one was refused), as a
    world document; :func:`room_problems` says whether it may be kept."""
    if kind not in KINDS:
        raise ValueError(f"no kind of generated world {kind!r} (kinds: {', '.join(KINDS)})")
    rng = random.Random(f"{kind}:{seed}:{attempt}")
    glassy = kind == "glass"
    hall = glassy and rng.random() < 0.25
    width = rng.uniform(16.0, 18.0) if hall else rng.uniform(5.0, 12.0 if glassy else 10.0)
    height = rng.uniform(12.0, 13.0) if hall else rng.uniform(4.0, 9.0 if glassy else 8.0)
    width, height = round(width, 2), round(height, 2)
    walls: list[list[list[float]]] = []
    glass: list[list[list[float]]] = []
    dock = _dock_on_a_wall(rng, width, height)
    if rng.random() < (0.5 if glassy else 0.35):
        opaque, panes = _partition(rng, width, height, glassy)
        walls += opaque
        glass += panes
    if glassy:
        if rng.random() < 0.5:
            glass += _alcove(rng, dock)
        for _ in range(rng.randint(2, 6 if hall else 4)):
            glass.append(_pane(rng, width, height, longest_m=6.0 if hall else 3.5))
    boxes = [_box(rng, width, height) for _ in range(rng.randint(0, 4))]
    start = _start(rng, width, height)
    return {
        "name": world_name(kind, seed, attempt),
        "bounds": [0.0, 0.0, width, height],
        "walls": walls,
        "glass": glass,
        "boxes": boxes,
        "docks": [{"id": "home", "pose": [round(v, 4) for v in dock.as_tuple()], "type": "charger"}],
        "robot": {"start": [round(v, 3) for v in start.as_tuple()]},
    }


def room_problems(doc: dict[str, Any]) -> list[str]:
    """Why a drawn room may not be kept (empty: it may): its document does not parse, something stands in
    the approach to the dock, or the start is nearer a surface than trials' starts may be (whatever its
    heading, the body then clears everything) or too near the dock."""
    try:
        world = parse_world(doc, doc.get("name", "<generated>"))
    except Exception as exc:  # a ConfigError naming the field
        return [str(exc)]
    problems = []
    dock = world.docks[0].pose2d
    for label, point in _feature_points(world):
        along, aside = dock.inverse().transform_point(*point)
        # the corridor runs back from the dock's face, against the robot's heading at the dock
        if -APPROACH_CLEAR_M <= along <= DOCK_BACK_M and abs(aside) <= APPROACH_HALF_WIDTH_M:
            problems.append(f"{label} stands in the approach to the dock")
            break
    start = Pose2D(*world.robot.start)
    segments = world.opaque_segments() + list(world.glass)
    if min(distance_to_segment((start.x, start.y), seg) for seg in segments) < START_CLEARANCE_M:
        problems.append("the start: too near a wall, a pane, a box or the dock")
    if start.distance_to(dock) < START_AWAY_M:
        problems.append("the start is too near the dock")
    return problems


# --- drawing ----------------------------------------------------------------------------------------


def _dock_on_a_wall(rng: random.Random, width: float, height: float) -> Pose2D:
    """The docked pose in front of a wall, facing it: the body's back against the wall."""
    back = DOCK_BACK_M
    side = rng.choice(("south", "north", "west", "east"))
    if side in ("south", "north"):
        x = rng.uniform(1.0, width - 1.0)
        return Pose2D(x, back, -math.pi / 2) if side == "south" else Pose2D(x, height - back, math.pi / 2)
    y = rng.uniform(1.0, height - 1.0)
    return Pose2D(back, y, math.pi) if side == "west" else Pose2D(width - back, y, 0.0)


def _partition(
    rng: random.Random, width: float, height: float, glassy: bool
) -> tuple[list[list[list[float]]], list[list[list[float]]]]:
    """A wall across the room with a door 1.0-1.6 m wide; in glass rooms part of it (or all) is glass."""
    across_x = width >= height
    span = height if across_x else width
    at = rng.uniform(0.35, 0.65) * (width if across_x else height)
    door = rng.uniform(1.0, 1.6)
    door_at = rng.uniform(0.3, span - door - 0.3)
    pieces = [(0.0, door_at), (door_at + door, span)]
    opaque: list[list[list[float]]] = []
    panes: list[list[list[float]]] = []
    for lo, hi in pieces:
        if hi - lo < 0.2:
            continue
        segment = [[at, lo], [at, hi]] if across_x else [[lo, at], [hi, at]]
        segment = [[round(x, 3), round(y, 3)] for x, y in segment]
        (panes if glassy and rng.random() < 0.7 else opaque).append(segment)
    return opaque, panes


def _alcove(rng: random.Random, dock: Pose2D) -> list[list[list[float]]]:
    """Two panes beside the dock, square to its wall: the dock at the back of an alcove of glass."""
    half = rng.uniform(0.55, 0.8)
    depth = rng.uniform(0.8, 1.4)
    back = DOCK_BACK_M
    panes = []
    for side in (-1.0, 1.0):
        a = dock.transform_point(back, side * half)
        b = dock.transform_point(back - depth, side * half)
        panes.append([[round(a[0], 3), round(a[1], 3)], [round(b[0], 3), round(b[1], 3)]])
    return panes


def _pane(rng: random.Random, width: float, height: float, longest_m: float) -> list[list[float]]:
    length = rng.uniform(0.8, longest_m)
    angle = rng.uniform(0.0, math.pi)
    dx, dy = 0.5 * length * math.cos(angle), 0.5 * length * math.sin(angle)
    m = EDGE_MARGIN_M
    cx = rng.uniform(m + abs(dx), max(m + abs(dx), width - m - abs(dx)))
    cy = rng.uniform(m + abs(dy), max(m + abs(dy), height - m - abs(dy)))
    return [[round(cx - dx, 3), round(cy - dy, 3)], [round(cx + dx, 3), round(cy + dy, 3)]]


def _box(rng: random.Random, width: float, height: float) -> dict[str, Any]:
    w, d = rng.uniform(0.3, 0.8), rng.uniform(0.3, 0.8)
    reach = 0.5 * math.hypot(w, d) + EDGE_MARGIN_M
    x, y = rng.uniform(reach, width - reach), rng.uniform(reach, height - reach)
    return {
        "pose": [round(x, 3), round(y, 3), round(rng.uniform(-math.pi, math.pi), 3)],
        "size": [round(w, 2), round(d, 2)],
    }


def _start(rng: random.Random, width: float, height: float) -> Pose2D:
    return Pose2D(
        rng.uniform(0.5, width - 0.5), rng.uniform(0.5, height - 0.5), rng.uniform(-math.pi, math.pi)
    )


def _feature_points(world: World) -> list[tuple[str, tuple[float, float]]]:
    """Points 2 cm apart along every inner wall, pane and box edge, each with what it belongs to."""
    out: list[tuple[str, tuple[float, float]]] = []
    segments = [(f"walls.{i}", s) for i, s in enumerate(world.walls)]
    segments += [(f"glass.{i}", s) for i, s in enumerate(world.glass)]
    for i, box in enumerate(world.boxes):
        corners = box.corners()
        segments += [(f"boxes.{i}", (corners[k], corners[(k + 1) % 4])) for k in range(4)]
    for label, (a, b) in segments:
        length = math.dist(a, b)
        for t in np.linspace(0.0, 1.0, max(2, int(length / 0.02) + 1)):
            out.append((label, (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))))
    return out
