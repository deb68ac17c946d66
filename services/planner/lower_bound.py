"""The time no robot could beat between two poses: the yardstick of ``zendock demo`` and ``trials``.

``lower_bound_s = L / v_max + turns / w_max``: ``L`` is the shortest collision-free path length for
the robot's inscribed circle with glass as solid as any wall (:mod:`services.planner.shortest_path`),
``turns`` the heading changes that path forces (from the start heading onto the first leg, at each
corner, and onto the goal heading). Each answer also gives ``way_width_m``, the widest way's narrowest
gap, glass solid (:mod:`services.planner.way_width`): how tight the way is that the bound assumes the
robot can take. Run it as a process so tools stay apart from the planner's code::

    python -m services.planner.lower_bound --world W --start X Y YAW --goal X Y YAW
    python -m services.planner.lower_bound --world W --batch   # JSON lines {"start": [...], "goal": [...]} on stdin
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

import numpy as np

from services.planner.astar import PlanningError
from services.planner.costmap import CostGrid
from services.planner.shortest_path import shortest_path, solid_grid, solid_map
from services.planner.smoothing import path_length_m
from services.planner.way_width import WayWidths
from shared.config_errors import ConfigError
from shared.geometry import Pose2D, wrap_angle
from shared.world import load_world

#: Legs shorter than this are left out of the turns: a last leg of a few centimetres into a docking
#: pose (see :data:`services.planner.shortest_path.END_SNAP_RADIUS_M`) points wherever the nearest free
#: cell happened to be, and turning onto it and off again is no turn the robot must make. Leaving turns
#: out only lowers the bound, which stays a bound.
MIN_TURNING_LEG_M = 0.11


def turns_rad(points: np.ndarray, start_yaw: float, goal_yaw: float) -> float:
    """Total heading change along a polyline driven forward, from ``start_yaw`` to ``goal_yaw``."""
    legs = np.diff(np.asarray(points, dtype=float), axis=0)
    legs = legs[np.hypot(legs[:, 0], legs[:, 1]) >= MIN_TURNING_LEG_M]
    if len(legs) == 0:
        return abs(wrap_angle(goal_yaw - start_yaw))
    headings = np.arctan2(legs[:, 1], legs[:, 0])
    total = abs(wrap_angle(headings[0] - start_yaw)) + abs(wrap_angle(goal_yaw - headings[-1]))
    total += float(sum(abs(wrap_angle(b - a)) for a, b in zip(headings[:-1], headings[1:])))
    return total


def lower_bound(
    grid: CostGrid, start: Pose2D, goal: Pose2D, max_linear_mps: float, max_angular_radps: float
) -> dict:
    points = shortest_path(grid, (start.x, start.y), (goal.x, goal.y))
    length = path_length_m(points)
    turn = turns_rad(points, start.yaw, goal.yaw)
    return {
        "path_length_m": round(length, 4),
        "turn_rad": round(turn, 4),
        "lower_bound_s": round(length / max_linear_mps + turn / max_angular_radps, 4),
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m services.planner.lower_bound", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--world", required=True)
    parser.add_argument("--start", type=float, nargs=3, metavar=("X", "Y", "YAW"))
    parser.add_argument("--goal", type=float, nargs=3, metavar=("X", "Y", "YAW"))
    parser.add_argument("--batch", action="store_true", help="read JSON lines of start/goal pairs on stdin")
    parser.add_argument("--max-linear", type=float, default=0.5, help="m/s")
    parser.add_argument("--max-angular", type=float, default=1.5, help="rad/s")
    args = parser.parse_args(argv)
    if not args.batch and (args.start is None or args.goal is None):
        parser.error("give --start and --goal, or --batch")
    try:
        world = load_world(args.world)
    except ConfigError as exc:
        print(f"{parser.prog}: {exc}", file=sys.stderr)
        return 2
    occupancy = solid_map(world)
    grid = solid_grid(world, occupancy=occupancy)
    ways: dict[tuple[float, float], WayWidths] = {}  # one search per goal, every start it is asked from
    queries = (
        [{"start": args.start, "goal": args.goal}]
        if not args.batch
        else [json.loads(line) for line in sys.stdin if line.strip()]
    )
    failed = 0
    for query in queries:
        try:
            start, goal = Pose2D(*query["start"]), Pose2D(*query["goal"])
            result = lower_bound(grid, start, goal, args.max_linear, args.max_angular)
            if (goal.x, goal.y) not in ways:
                ways[(goal.x, goal.y)] = WayWidths(occupancy, (goal.x, goal.y))
            result["way_width_m"] = round(ways[(goal.x, goal.y)].width_m((start.x, start.y)), 3)
        except (PlanningError, KeyError, TypeError, ValueError) as exc:
            failed += 1
            result = {"error": str(exc), "lower_bound_s": None}
        print(json.dumps(result, allow_nan=False), flush=True)
    return 1 if failed and not args.batch else 0


if __name__ == "__main__":
    sys.exit(main())
