"""Infrared docking on the kinematic model, in world files: how often it docks, how long it takes, why it fails.

The full stack's campaign (``zendock trials --controller ir``) is the figure of record, but it costs
minutes of a machine per world and its rare failures hide in logs. This bench closes the same task
(:class:`~services.docking.ir_run.IrDockingRun`, the service's own state machine) in a loop with the
simulator's own beacon model (:func:`shared.models.infrared.receiver_readings`: fields, fields of
view, occlusion, dropout) on a unicycle with the base's acceleration limits, from the same beacon
starts as the trials (:func:`shared.starts.beacon_starts`), in any world file:

- the readings reach the task one control tick late (20 Hz), as they cross the bus;
- walls, boxes, glass and dock bodies are solid: a motion that would overlap one does not happen (the
  robot pushes against it) and counts as a collision; the plate the robot docks on instead stops it
  along the dock's axis and turns it towards flush as it pushes, as the simulator's rigid bodies do,
  and such a touch is no collision (the simulator's "docking touch");
- the obstacle checks ahead and behind see walls, boxes, the docks and glass within 0.3 m of the robot's
  front and rear (the service's lidar and sonar checks, which infrared docking runs without the dock's
  exemption);
- the contacts mate as the simulator's do (within 5 cm short of the dock pose, 4 cm and 0.1 rad), and
  mating is charging.

It runs in a process of its own, apart from the stack::

    python -m services.docking.ir_bench --world deploy/worlds/unseen --n 50 --seed 1 [--json]

Each failure is printed with its start and the states it went through, which is what a long run in
the full stack's log (``infrared: ...`` lines) shows too.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from services.docking.ir_drive import IrDriveParams
from services.docking.ir_run import IrDockingRun
from services.docking.kinematics import DiffDriveModel
from services.docking.task_io import Outcome, TickInputs, Velocity
from shared.config_errors import ConfigError
from shared.geometry import Pose2D, wrap_angle
from shared.models.dock_contact import DockContactParams
from shared.models.infrared import InfraredParams, receiver_readings
from shared.models.raycast import SegmentSet
from shared.starts import beacon_starts
from shared.world import (
    DOCK_GEOMETRY,
    ROBOT_FRONT_M,
    ROBOT_LENGTH_M,
    ROBOT_WIDTH_M,
    World,
    load_world,
    world_files,
)

DT_S = 0.05
#: Points along every solid surface this far apart: what the footprint and the check ahead test against.
SURFACE_STEP_M = 0.01
STOP_DISTANCE_M = 0.3
SIDE_MARGIN_M = 0.05
#: The simulator's own mating tolerances.
MATING = DockContactParams()


@dataclass
class IrTrial:
    start: tuple[float, float, float]
    docked: bool
    time_s: float
    lateral_error_m: float
    yaw_error_rad: float
    collisions: int
    outcome: str
    #: The drive's states in order, repeats collapsed (what a failure went through).
    states: list[str] = field(default_factory=list)


def _surface_points(segments: Sequence[tuple[tuple[float, float], tuple[float, float]]]) -> np.ndarray:
    points = []
    for (ax, ay), (bx, by) in segments:
        n = max(2, int(math.hypot(bx - ax, by - ay) / SURFACE_STEP_M) + 1)
        t = np.linspace(0.0, 1.0, n)
        points.append(np.column_stack((ax + t * (bx - ax), ay + t * (by - ay))))
    return np.vstack(points) if points else np.zeros((0, 2))


class Room:
    """A world's solid surfaces as points, and its infrared occluders, for one dock."""

    def __init__(self, world: World) -> None:
        self.world = world
        self.dock = world.docks[0].pose2d
        self.occluders = SegmentSet(world.opaque_segments())
        body = DOCK_GEOMETRY.body_box(world.docks[0]).corners()
        self.plate = _surface_points([(body[i], body[(i + 1) % 4]) for i in range(4)])
        others = [s for s in world.opaque_segments() if not _is_edge_of(s, body)]
        self.solid = _surface_points(others + list(world.glass))
        self.seen = _surface_points(world.opaque_segments() + list(world.glass))

    def overlaps(self, pose: Pose2D, points: np.ndarray) -> bool:
        local = pose.inverse().transform_points(points)
        return bool(
            np.any((np.abs(local[:, 0]) <= ROBOT_LENGTH_M / 2) & (np.abs(local[:, 1]) <= ROBOT_WIDTH_M / 2))
        )

    def blocked(self, pose: Pose2D, direction: float) -> bool:
        """Something within ``STOP_DISTANCE_M`` of the robot's front (``direction`` +1) or rear (-1)."""
        local = pose.inverse().transform_points(self.seen)
        along, side = direction * local[:, 0] - ROBOT_FRONT_M, np.abs(local[:, 1])
        return bool(
            np.any((along > 0.0) & (along <= STOP_DISTANCE_M) & (side <= ROBOT_WIDTH_M / 2 + SIDE_MARGIN_M))
        )

    def pressed_flush(self, pose: Pose2D, moved: Pose2D, pushed_m: float) -> Pose2D:
        """Where the plate leaves a robot that pushed ``pushed_m`` into it from ``pose``: no further along the
        axis than its front allows, its heading turned towards the dock's by what the push lets a corner
        pivot (the push over half the robot's width)."""
        error = wrap_angle(moved.yaw - self.dock.yaw)
        turn = min(abs(error), abs(pushed_m) / (ROBOT_WIDTH_M / 2))
        yaw = moved.yaw - math.copysign(turn, error)
        local = Pose2D(moved.x, moved.y, yaw).relative_to(self.dock)
        reach = -(ROBOT_WIDTH_M / 2) * abs(
            math.sin(wrap_angle(yaw - self.dock.yaw))
        )  # a corner touches first
        along = min(local.x, max(pose.relative_to(self.dock).x, reach))
        return self.dock.compose(Pose2D(along, local.y, local.yaw))

    def mated(self, pose: Pose2D) -> tuple[bool, Pose2D]:
        offset = pose.relative_to(self.dock)
        yaw = wrap_angle(pose.yaw - self.dock.yaw)
        return (
            -MATING.contact_reach_m <= offset.x <= MATING.overshoot_slack_m
            and abs(offset.y) <= MATING.max_lateral_error_m
            and abs(yaw) <= MATING.max_yaw_error_rad
        ), offset


def _is_edge_of(
    segment: tuple[tuple[float, float], tuple[float, float]], corners: list[tuple[float, float]]
) -> bool:
    return all(any(math.dist(end, c) < 1e-9 for c in corners) for end in segment)


def dock_from(
    room: Room, start: Pose2D, seed: int, max_time_s: float = 180.0, drive: IrDriveParams | None = None
) -> IrTrial:
    """One infrared docking from ``start`` (see the module docstring)."""
    rng = np.random.default_rng(seed)
    params = InfraredParams()
    task = IrDockingRun(drive, max_time_s=max_time_s)
    base = DiffDriveModel(start)
    pose, t, collisions, touching = start, 0.0, 0, False
    late = receiver_readings(pose, room.world.docks, room.occluders, params, rng)
    states: list[str] = []
    while True:
        mated, offset = room.mated(pose)
        readings, late = late, receiver_readings(pose, room.world.docks, room.occluders, params, rng)
        intent = task.step(
            TickInputs(
                now_s=t,
                base_twist=(base.v_mps, base.w_radps),
                charging=mated,
                blocked_ahead=room.blocked(pose, 1.0),
                blocked_behind=room.blocked(pose, -1.0),
                ir_dock=readings,
            )
        )
        state = task.drive.state.value
        if not states or states[-1] != state:
            states.append(state)
        if task.result is not None:
            docked = task.result.outcome is Outcome.SUCCEEDED
            return IrTrial(
                start.as_tuple(),
                docked,
                t,
                abs(offset.y) if docked else math.nan,
                abs(wrap_angle(pose.yaw - room.dock.yaw)) if docked else math.nan,
                collisions,
                task.result.message or task.result.outcome.value,
                states,
            )
        command = intent if isinstance(intent, Velocity) else Velocity(0.0, 0.0)
        before = (base.x, base.y, base.yaw, base.v_mps, base.w_radps)
        base.step(command.linear_x_mps, command.angular_z_radps, DT_S)
        moved = Pose2D(base.x, base.y, base.yaw)
        hit = room.overlaps(moved, room.solid)
        if not hit and room.overlaps(moved, room.plate) and not room.mated(moved)[0]:
            moved = room.pressed_flush(pose, moved, base.v_mps * DT_S)
            base.x, base.y, base.yaw = moved.x, moved.y, moved.yaw
            hit = room.overlaps(moved, room.solid)
        if hit:  # solid: the robot pushes against it and stays where it was
            base.x, base.y, base.yaw = before[:3]
            base.v_mps = base.w_radps = 0.0
            collisions += 0 if touching else 1
        else:
            pose = moved
        touching = hit
        t += DT_S


def run(worlds: Sequence[Path], n: int, seed: int, max_time_s: float = 180.0) -> dict:
    per_world: dict[str, dict] = {}
    everything: list[IrTrial] = []
    for number, path in enumerate(worlds):
        world = load_world(path)
        if not world.docks:
            raise ConfigError(f"{path}: the world has no dock")
        room = Room(world)
        trials = [
            dock_from(room, start, seed + 1000 * number + i, max_time_s)
            for i, start in enumerate(beacon_starts(world, n, seed + 1000 * number))
        ]
        everything += trials
        per_world[world.name] = _summary(trials)
    return {
        "summary": _summary(everything),
        "worlds": per_world,
        "failures": [asdict(t) for t in everything if not t.docked],
    }


def _summary(trials: list[IrTrial]) -> dict:
    docked = [t for t in trials if t.docked]
    times = sorted(t.time_s for t in docked)
    lateral = sorted(t.lateral_error_m for t in docked)
    return {
        "n": len(trials),
        "docked": len(docked),
        "success_rate": len(docked) / len(trials) if trials else math.nan,
        "collisions": sum(t.collisions for t in trials),
        "median_time_s": round(statistics.median(times), 2) if times else None,
        "p95_time_s": round(times[min(len(times) - 1, int(0.95 * len(times)))], 2) if times else None,
        "max_time_s": round(times[-1], 2) if times else None,
        "median_lateral_error_m": round(statistics.median(lateral), 4) if lateral else None,
        "p95_lateral_error_m": round(lateral[min(len(lateral) - 1, int(0.95 * len(lateral)))], 4)
        if lateral
        else None,
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m services.docking.ir_bench", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--world",
        action="append",
        required=True,
        metavar="FILE|DIR",
        help="world file or directory of them (repeatable)",
    )
    parser.add_argument("--n", type=int, default=20, help="beacon starts per world")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--max-time", type=float, default=180.0, help="the run's time limit (s), as the service's"
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    try:
        report = run(world_files(args.world), args.n, args.seed, args.max_time)
    except (ConfigError, OSError, ValueError, RuntimeError) as exc:
        print(f"ir_bench: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(report))
        return 0
    for name, row in {**report["worlds"], "all": report["summary"]}.items():
        print(
            f"{name:16s} {row['docked']}/{row['n']} docked, {row['collisions']} collisions, time median "
            f"{row['median_time_s']} s p95 {row['p95_time_s']} max {row['max_time_s']}, lateral median "
            f"{row['median_lateral_error_m']} p95 {row['p95_lateral_error_m']} m"
        )
    for failure in report["failures"]:
        print(
            f"failed from {tuple(round(v, 2) for v in failure['start'])}: {failure['outcome']}; states "
            f"{' > '.join(failure['states'][-12:])}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
