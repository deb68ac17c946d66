"""Docking controller benchmark on the kinematic model: the seed line approach against the graceful law.

Every controller starts from the same grid of poses in the staging area behind the dock (distance
back, lateral offset, yaw offset), sees the robot's pose late and noisy as the real stack delivers it,
and drives until the contacts touch. Reported per controller: median time to contact, median
lateral and yaw error at contact, and how many runs mated. ``python -m services.docking.bench``
prints the table.

The seed controller gets the line-approach waypoints that are still ahead of its start (the front
waypoint and the dock, or only the dock when it starts closer than the front waypoint); its full
run from its own staging goal is reported separately as ``seed_full_run``. The tuned graceful
controller's pose estimator is given the true latency, as the service gives it the age of each pose.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
from collections.abc import Callable, Sequence
from dataclasses import asdict, replace
from typing import Any

from services.docking.approach import (
    DEFAULT_LINE_OFFSETS,
    LineApproachOffsets,
    dock_frame_error,
    line_approach,
    offset_along,
)
from services.docking.graceful import NAV2_DOCKING_PARAMS, ZENDOCK_PARAMS, GracefulDockController
from services.docking.kinematics import (
    ApproachResult,
    DockingController,
    MatingTolerance,
    PoseSensing,
    RobotLimits,
    simulate_approach,
)
from services.docking.seed_controller import LineApproachController, LineApproachParams
from shared.geometry import Pose2D

#: The seed room's dock: ``deploy/worlds/seed_room.yaml``.
SEED_ROOM_DOCK = Pose2D(-1.0, 0.83, -math.pi / 2)

GRID_BACK_M = (0.5, 0.75, 1.0)
GRID_LATERAL_M = (-0.15, 0.0, 0.15)
GRID_YAW_RAD = (-0.3, 0.0, 0.3)

#: Builds a controller from (start pose, dock pose, pose latency in s, control period in s).
ControllerFactory = Callable[[Pose2D, Pose2D, float, float], DockingController]


def staging_grid(
    dock_pose: Pose2D,
    back_m: Sequence[float] = GRID_BACK_M,
    lateral_m: Sequence[float] = GRID_LATERAL_M,
    yaw_rad: Sequence[float] = GRID_YAW_RAD,
) -> list[Pose2D]:
    """Start poses behind the dock: every combination of distance back, lateral offset and yaw offset."""
    return [offset_along(dock_pose, -b, lat, yaw) for b in back_m for lat in lateral_m for yaw in yaw_rad]


def seed_goals_ahead(
    start_pose: Pose2D, dock_pose: Pose2D, offsets: LineApproachOffsets = DEFAULT_LINE_OFFSETS
) -> list[Pose2D]:
    """The line approach's goals that lie ahead of ``start_pose`` along the dock axis (the dock always)."""
    params = LineApproachParams()
    start_along = dock_frame_error(start_pose, dock_pose).along_m
    goals = line_approach(dock_pose, offsets).goals
    ahead = [
        g
        for g in goals[:-1]
        if dock_frame_error(g, dock_pose).along_m > start_along + params.distance_tolerance_m
    ]
    return ahead + [goals[-1]]


def _seed_factory(start: Pose2D, dock: Pose2D, latency_s: float, period_s: float) -> DockingController:
    return LineApproachController(
        seed_goals_ahead(start, dock), LineApproachParams(control_period_s=period_s)
    )


def _nav2_factory(start: Pose2D, dock: Pose2D, latency_s: float, period_s: float) -> DockingController:
    return GracefulDockController(dock, replace(NAV2_DOCKING_PARAMS, control_period_s=period_s))


def _zendock_factory(start: Pose2D, dock: Pose2D, latency_s: float, period_s: float) -> DockingController:
    """The tuned controller; its pose estimator is told the latency (the service reads it from stamps)."""
    params = ZENDOCK_PARAMS
    if params.pose_estimator is not None:
        params = replace(params, pose_estimator=replace(params.pose_estimator, latency_s=latency_s))
    return GracefulDockController(dock, replace(params, control_period_s=period_s))


#: name -> (description, factory, control period in seconds)
CONTROLLERS: dict[str, tuple[str, ControllerFactory, float]] = {
    "seed": ("line approach, bang-bang 0.08 m/s / 0.1 rad/s, 10 Hz", _seed_factory, 0.1),
    "graceful_nav2": ("graceful law, Nav2 docking defaults, target = dock pose, 20 Hz", _nav2_factory, 0.05),
    "graceful_zendock": (
        "graceful law, ZENDOCK_TUNED, target past the plate, pose estimator, 20 Hz",
        _zendock_factory,
        0.05,
    ),
}


def summarise(results: Sequence[ApproachResult]) -> dict[str, Any]:
    """Medians and worst cases over the runs that reached contact; counts over all runs."""
    reached = [r for r in results if r.contact]
    summary: dict[str, Any] = {
        "runs": len(results),
        "contacts": len(reached),
        "mated": sum(r.mated for r in results),
    }
    if not reached:
        return summary | {
            "median_time_s": None,
            "median_lateral_error_mm": None,
            "median_yaw_error_deg": None,
        }
    lateral_mm = [abs(r.lateral_error_m) * 1000.0 for r in reached]
    yaw_deg = [abs(math.degrees(r.yaw_error_rad)) for r in reached]
    return summary | {
        "median_time_s": statistics.median(r.time_s for r in reached),
        "max_time_s": max(r.time_s for r in reached),
        "median_lateral_error_mm": statistics.median(lateral_mm),
        "max_lateral_error_mm": max(lateral_mm),
        "median_yaw_error_deg": statistics.median(yaw_deg),
        "max_yaw_error_deg": max(yaw_deg),
        "median_contact_speed_mps": statistics.median(r.contact_speed_mps for r in reached),
    }


def compare_controllers(
    dock_pose: Pose2D = SEED_ROOM_DOCK,
    starts: Sequence[Pose2D] | None = None,
    *,
    controllers: Sequence[str] = tuple(CONTROLLERS),
    sensing: PoseSensing | None = None,
    limits: RobotLimits | None = None,
    mating: MatingTolerance | None = None,
    timeout_s: float = 120.0,
    include_seed_full_run: bool = True,
) -> dict[str, Any]:
    """Run every controller from every start; returns a JSON-friendly dict (see :func:`format_comparison`).

    ``sensing`` defaults to 50 ms pose latency with 2 mm / 0.2 degree Gaussian noise; each run draws its
    own noise (seed ``sensing.seed + run index``), the same for every controller.
    """
    sensing = sensing or PoseSensing(latency_s=0.05, position_noise_m=0.002, yaw_noise_rad=math.radians(0.2))
    limits = limits or RobotLimits()
    mating = mating or MatingTolerance()
    starts = list(starts) if starts is not None else staging_grid(dock_pose)
    report: dict[str, Any] = {
        "dock_pose": list(dock_pose.as_tuple()),
        "starts": len(starts),
        "sensing": asdict(sensing),
        "limits": asdict(limits),
        "mating": asdict(mating),
        "controllers": {},
    }
    for name in controllers:
        description, factory, period_s = CONTROLLERS[name]
        results = []
        for i, start in enumerate(starts):
            run_sensing = PoseSensing(
                sensing.latency_s, sensing.position_noise_m, sensing.yaw_noise_rad, sensing.seed + i
            )
            results.append(
                simulate_approach(
                    factory(start, dock_pose, sensing.latency_s, period_s),
                    start,
                    dock_pose,
                    period_s,
                    limits=limits,
                    sensing=run_sensing,
                    mating=mating,
                    timeout_s=timeout_s,
                )
            )
        report["controllers"][name] = {"description": description, "control_period_s": period_s} | summarise(
            results
        )
    if include_seed_full_run:
        approach = line_approach(dock_pose)
        full = simulate_approach(
            LineApproachController(approach.goals),
            approach.staging_goal,
            dock_pose,
            CONTROLLERS["seed"][2],
            limits=limits,
            sensing=sensing,
            mating=mating,
            timeout_s=max(timeout_s, 300.0),
        )
        report["seed_full_run"] = {
            "start_pose": list(approach.staging_goal.as_tuple()),
            "contact": full.contact,
            "mated": full.mated,
            "time_s": full.time_s,
            "lateral_error_mm": abs(full.lateral_error_m) * 1000.0,
            "yaw_error_deg": abs(math.degrees(full.yaw_error_rad)),
        }
    return report


def _fmt(value: float | None, digits: int) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def format_comparison(report: dict[str, Any]) -> str:
    """A plain-text table of :func:`compare_controllers`' report."""
    s = report["sensing"]
    lines = [
        f"dock {report['dock_pose']}, {report['starts']} starts; pose latency {s['latency_s'] * 1000:.0f} ms, "
        f"noise {s['position_noise_m'] * 1000:.1f} mm / {math.degrees(s['yaw_noise_rad']):.2f} deg (1 sigma)",
        f"{'controller':<18} {'mated':>7} {'time s':>8} {'lat mm':>8} {'yaw deg':>8} "
        f"{'max lat':>8} {'max yaw':>8} {'v@contact':>9}",
    ]
    for name, row in report["controllers"].items():
        lines.append(
            f"{name:<18} {row['mated']:>3}/{row['runs']:<3} {_fmt(row['median_time_s'], 2):>8} "
            f"{_fmt(row['median_lateral_error_mm'], 2):>8} {_fmt(row['median_yaw_error_deg'], 2):>8} "
            f"{_fmt(row.get('max_lateral_error_mm'), 2):>8} {_fmt(row.get('max_yaw_error_deg'), 2):>8} "
            f"{_fmt(row.get('median_contact_speed_mps'), 2):>9}"
        )
    if "seed_full_run" in report:
        full = report["seed_full_run"]
        lines.append(
            f"seed from its staging goal {full['start_pose'][:2]}: {full['time_s']:.1f} s, "
            f"lateral {full['lateral_error_mm']:.1f} mm, yaw {full['yaw_error_deg']:.2f} deg, mated {full['mated']}"
        )
    return "\n".join(lines)


def main(
    latency_s: float, position_noise_m: float, yaw_noise_deg: float, seed: int, as_json: bool = False
) -> int:
    sensing = PoseSensing(latency_s, position_noise_m, math.radians(yaw_noise_deg), seed)
    report = compare_controllers(sensing=sensing)
    print(json.dumps(report, default=str) if as_json else format_comparison(report))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="Compare docking controllers on the kinematic model.")
    parser.add_argument("--latency", type=float, default=0.05, help="pose latency, s")
    parser.add_argument(
        "--position-noise", type=float, default=0.002, help="pose position noise (1 sigma), m"
    )
    parser.add_argument("--yaw-noise", type=float, default=0.2, help="pose yaw noise (1 sigma), degrees")
    parser.add_argument("--seed", type=int, default=0, help="noise seed")
    parser.add_argument("--json", action="store_true", help="one JSON line instead of the table")
    args = parser.parse_args()
    raise SystemExit(main(args.latency, args.position_noise, args.yaw_noise, args.seed, args.json))
