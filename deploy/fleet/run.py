"""``zendock fleet``: a fleet patrols one room for a stretch of simulated time, docking when low.

The run writes the effective world (:mod:`deploy.fleet.world_setup`) and the stack
(:mod:`deploy.fleet.stack`) into its run directory, starts the stack, staggers the robots' charges so
that they do not all need a dock at once, and watches the bus (:class:`~deploy.fleet.monitor.FleetMonitor`)
until the simulator's clock has moved on by the duration. The report (``fleet.json``), the tracks
(``tracks.json``) and the picture (``fleet.png``: every robot's track over the room, with the docks and
the robot-robot contacts) go into the run directory with every service's log.
"""

from __future__ import annotations

import math
import random
import statistics
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import yaml

from deploy import strict_json
from deploy.fleet.monitor import Conflict, FleetMonitor, RobotTally
from deploy.fleet.stack import FleetOptions, fleet_stack
from deploy.fleet.world_setup import fleet_world
from deploy.launcher import Launcher, free_endpoint
from deploy.memory import PeakRssSampler
from deploy.paths import REPO_ROOT, new_run_dir
from deploy.replacements import replacements_report
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest
from shared.names import topic_key
from shared.node import ServiceError, call_service
from shared.session import SessionSpec, open_session
from shared.world import World

#: Starting charges are spread over this range (the first robot full), so the robots run low in turn.
START_CHARGE = (1.0, 0.45)
#: A give-way longer than this (sim seconds) counts as long in the report: two robots waited on each other.
LONG_GIVE_WAY_S = 20.0
#: How often the progress is reported (wall seconds) by default: a line in a log; a terminal's live table asks more often.
PROGRESS_PERIOD_S = 10.0


@dataclass
class RobotReport:
    name: str
    distance_m: float
    dockings: int
    min_battery: float
    wait_s: float
    collisions: int
    collision_kinds: dict[str, int] = field(default_factory=dict)
    #: Each time it gave way to another robot: how long until the way was clear (sim seconds).
    give_ways_s: list[float] = field(default_factory=list)


@dataclass
class FleetReport:
    world: str
    robots: list[RobotReport]
    docks: int
    collisions: dict[str, int]
    reservation_conflicts: int
    conflicts: list[str]
    #: Robots giving way to each other: how often, the longest and the median until the way was clear (sim
    #: seconds), and how many lasted longer than :data:`LONG_GIVE_WAY_S`.
    give_ways: int
    max_give_way_s: float | None
    median_give_way_s: float | None
    long_give_ways: int
    sim_s: float
    wall_s: float
    achieved_rtf: float
    peak_rss_mb: dict[str, float]
    errors: list[str]
    #: Each replaced service and the command that ran in its place (``--service``): whose figures these are.
    replaced_services: dict[str, str] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["robots"] = [
            {
                **r,
                "min_battery": round(r["min_battery"], 4),
                "distance_m": round(r["distance_m"], 1),
                "wait_s": round(r["wait_s"], 1),
                "give_ways_s": [round(g, 1) for g in r["give_ways_s"]],
            }
            for r in data["robots"]
        ]
        data["sim_s"], data["wall_s"] = round(self.sim_s, 1), round(self.wall_s, 1)
        return data


def run_fleet(
    options: FleetOptions,
    log: Callable[[str], None] = print,
    progress: Callable[[float, list[RobotTally]], None] | None = None,
    progress_period_s: float = PROGRESS_PERIOD_S,
) -> tuple[FleetReport, Path]:
    """Run the fleet; returns the report and the run directory.

    ``progress(sim seconds so far, robots)`` is called every ``progress_period_s`` wall seconds.
    """
    run_dir = new_run_dir(options.runs_dir, "fleet-", f"-{options.world.stem}")
    world, world_file = fleet_world(options.world, options.robots, options.seed, run_dir / "world.yaml")
    robots = [r.name for r in world.robots]
    endpoint = free_endpoint()
    stack = fleet_stack(options, endpoint, world_file, robots, run_dir / "state")
    # The run's record of what ran (as ``zendock config`` prints a stack), not read back.
    (run_dir / "stack.yaml").write_text(yaml.safe_dump(stack.to_dict(), sort_keys=False))
    log(
        f"{len(robots)} robot(s) and {len(world.docks)} dock(s) in {world.name} for {options.duration_s:g} s of "
        f"simulated time, rtf {options.rtf}, detector {options.detector}; run directory {run_dir}"
        + "".join(f"; {r.name} replaced by `{r.command}`" for r in options.replacements)
    )
    errors: list[str] = []
    wall_start = time.monotonic()
    with Launcher(
        stack, project_dir=run_dir / "stack", working_dir=REPO_ROOT, project_name="fleet"
    ) as launcher:
        launcher.wait_healthy(timeout_s=180.0)
        sampler = PeakRssSampler(lambda: [(s.name, s.pid) for s in launcher.ps()])
        with sampler, open_session(SessionSpec(connect=(endpoint,))) as session:
            monitor = FleetMonitor(session, robots)
            try:
                _stagger_charges(session, robots, options.seed, errors)
                sim_start, sim_end, wall_run = _watch(
                    monitor, options.duration_s, progress, progress_period_s
                )
                sim_now, tallies, conflicts, contacts = monitor.snapshot()
            finally:
                monitor.close()
        for status in launcher.ps():
            (run_dir / f"{status.name}.log").write_text("\n".join(launcher.logs(status.name)) + "\n")
    sim_s = sim_end - sim_start
    report = _report(
        world,
        tallies,
        conflicts,
        contacts,
        sim_s,
        time.monotonic() - wall_start,
        sim_s / max(wall_run, 1e-9),
        dict(sampler.peak_mb),
        errors,
    )
    report.replaced_services = replacements_report(options.replacements)
    (run_dir / "fleet.json").write_text(strict_json.dumps(report.to_json(), indent=2) + "\n")
    # Every robot's ground-truth track (x, y every 10 cm; 20, 40 ... once thinned past TRACK_POINTS_MAX).
    tracks = {t.name: [[round(x, 2), round(y, 2)] for x, y in t.track] for t in tallies}
    (run_dir / "tracks.json").write_text(strict_json.dumps(tracks) + "\n")
    from deploy.fleet.picture import plot_fleet  # noqa: PLC0415 - matplotlib is slow to import

    plot_fleet(world, tallies, contacts, run_dir / "fleet.png")
    return report, run_dir


def _stagger_charges(session: Any, robots: list[str], seed: int, errors: list[str]) -> None:
    """Spread the starting charges; the seed decides who gets which (and so who has priority)."""
    high, low = START_CHARGE
    order = list(robots)
    random.Random(seed).shuffle(order)
    for i, robot in enumerate(order):
        charge = high - (high - low) * i / max(1, len(robots) - 1)
        try:
            call_service(
                session,
                topic_key(robot, "battery/set_state"),
                SET_BATTERY_STATE,
                SetBatteryStateRequest(percentage=charge),
                timeout_s=10.0,
            )
        except ServiceError as exc:
            errors.append(f"{robot}: starting charge not set: {exc}")


def _watch(
    monitor: FleetMonitor,
    duration_s: float,
    progress: Callable[[float, list[RobotTally]], None] | None,
    progress_period_s: float = PROGRESS_PERIOD_S,
) -> tuple[float, float, float]:
    """Wait until the sim clock has run ``duration_s``; (sim start, sim end, wall seconds)."""
    deadline = time.monotonic() + 60.0
    while not math.isfinite(monitor.sim_time()):
        if time.monotonic() > deadline:
            raise ServiceError("no clock from the simulator within 60 s")
        time.sleep(0.2)
    sim_start = monitor.sim_time()
    wall_start = time.monotonic()
    last_progress = -math.inf
    last_clock, last_clock_wall = sim_start, wall_start
    while True:
        sim_now = monitor.sim_time()
        if sim_now - sim_start >= duration_s:
            return sim_start, sim_now, time.monotonic() - wall_start
        if sim_now != last_clock:
            last_clock, last_clock_wall = sim_now, time.monotonic()
        elif time.monotonic() - last_clock_wall > 60.0:
            raise ServiceError(f"the simulator's clock stopped at {sim_now:.1f} s")
        if progress is not None and time.monotonic() - last_progress >= progress_period_s:
            last_progress = time.monotonic()
            sim_now, tallies, _, _ = monitor.snapshot(tracks=False)
            progress(sim_now - sim_start, tallies)
        time.sleep(0.5)


def _report(
    world: World,
    tallies: list[RobotTally],
    conflicts: list[Conflict],
    contacts: list[tuple[float, float, float, str, str]],
    sim_s: float,
    wall_s: float,
    rtf: float,
    peak_rss_mb: dict[str, float],
    errors: list[str],
) -> FleetReport:
    robots = [
        RobotReport(
            t.name,
            t.distance_m,
            t.dockings,
            t.min_battery if math.isfinite(t.min_battery) else 0.0,
            t.wait_s,
            t.collisions,
            t.collision_kinds,
            t.give_ways_s,
        )
        for t in tallies
    ]
    give_ways = [g for t in tallies for g in t.give_ways_s]
    world_hits = sum(n for t in tallies for kind, n in t.collision_kinds.items() if kind != "robot")
    return FleetReport(
        world=world.name,
        robots=robots,
        docks=len(world.docks),
        collisions={
            "total": world_hits + len(contacts),
            "robot_robot": len(contacts),
            "robot_world": world_hits,
        },
        reservation_conflicts=len(conflicts),
        conflicts=[c.describe() for c in conflicts],
        give_ways=len(give_ways),
        max_give_way_s=round(max(give_ways), 1) if give_ways else None,
        median_give_way_s=round(statistics.median(give_ways), 1) if give_ways else None,
        long_give_ways=sum(1 for g in give_ways if g > LONG_GIVE_WAY_S),
        sim_s=sim_s,
        wall_s=wall_s,
        achieved_rtf=round(rtf, 2),
        peak_rss_mb=peak_rss_mb,
        errors=errors,
    )
