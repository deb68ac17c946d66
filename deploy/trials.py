"""``zendock trials``: many dockings from random starts on the full distributed stack, measured.

One stack serves ``workers`` robots at once: a single simulator process steps one copy of the room per
robot (namespaces ``r0``, ``r1``, …), and each robot has its own battery, pose, planner and docking
services, exactly the processes the default stack runs. Each trial places its robot at a random
collision-free start (seeded, reproducible), sets the battery just above the low threshold and waits
for ``CHARGING``; the :class:`~deploy.observer.RunObserver` measures it on ground truth. Noise and a
map->odom localisation error are on, as on a real robot.
"""

from __future__ import annotations

import json
import math
import queue
import random
import statistics
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import yaml

from deploy.launcher import Launcher, free_endpoint, load_stack
from deploy.memory import PeakRssSampler
from deploy.observer import RunObserver, RunRecord
from shared.geometry import Pose2D
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest
from shared.interfaces.simulator import SIM_STATE, TELEPORT, SimStateRequest, TeleportRequest
from shared.names import topic_key
from shared.node import ServiceError, ServiceUnavailable, call_service
from shared.session import SessionSpec, open_session
from shared.world import World, load_world

REPO_ROOT = Path(__file__).resolve().parents[1]
#: The robot's circumscribed radius plus a margin: starts this far from every surface can always turn.
START_CLEARANCE_M = 0.45
#: Starts at least this far from the dock, so each trial navigates before it docks.
MIN_START_DISTANCE_TO_DOCK_M = 1.2


@dataclass(frozen=True)
class TrialOptions:
    world: Path
    n: int = 10
    controller: str = "graceful"
    seed: int = 0
    rtf: str = "8"
    workers: int = 1
    timeout_sim_s: float = 240.0
    localisation_error: tuple[float, float, float] = (0.03, -0.02, 0.02)
    battery_start: float = 0.255
    drain_scale: float = 20.0
    runs_dir: Path = REPO_ROOT / "runs"
    #: Fault injection: every ``chaos_period_s`` wall seconds on average, kill -9 a random robot service
    #: (battery, pose, planner or docking; never the simulator) and let the launcher restart it. 0: off.
    chaos_period_s: float = 0.0


@dataclass
class ChaosReport:
    kills: int = 0
    recovered: int = 0
    recovery_s: list[float] = field(default_factory=list)
    killed: list[str] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        times = sorted(self.recovery_s)
        return {
            "kills": self.kills,
            "recovered": self.recovered,
            "median_recovery_s": round(statistics.median(times), 2) if times else math.nan,
            "max_recovery_s": round(times[-1], 2) if times else math.nan,
            "killed": self.killed,
            "recovery_s": [round(t, 3) for t in self.recovery_s],
        }


class ChaosMonkey:
    """Kills random robot services at random times while trials run; measures how fast each comes back."""

    VICTIMS = ("battery", "pose", "planner", "docking")

    def __init__(self, launcher: Launcher, robots: list[str], period_s: float, seed: int) -> None:
        self._launcher = launcher
        self._names = [f"{v}_{r}" for r in robots for v in self.VICTIMS]
        self._period_s = period_s
        self._rng = random.Random(seed + 1)
        self._stop = threading.Event()
        self.report = ChaosReport()
        self._thread = threading.Thread(target=self._run, name="chaos", daemon=True)

    def __enter__(self) -> ChaosMonkey:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=60.0)

    def _run(self) -> None:
        while not self._stop.wait(self._rng.expovariate(1.0 / self._period_s)):
            name = self._rng.choice(self._names)
            try:
                before = self._launcher.status(name).starts
                self._launcher.kill(name)
            except Exception:  # the stack is going down
                return
            killed_at = time.monotonic()
            self.report.kills += 1
            self.report.killed.append(name)
            deadline = killed_at + 60.0
            while time.monotonic() < deadline and not self._stop.is_set():
                status = self._launcher.status(name)
                if status.starts > before and status.health == "healthy":
                    self.report.recovered += 1
                    self.report.recovery_s.append(time.monotonic() - killed_at)
                    break
                time.sleep(0.05)


@dataclass
class TrialResult:
    index: int
    robot: str
    start: tuple[float, float, float]
    docked: bool
    charging: bool
    dock_time_s: float
    lateral_error_m: float
    yaw_error_rad: float
    collisions: int
    path_length_m: float
    lower_bound_s: float = math.nan
    wall_s: float = 0.0
    sim_s: float = 0.0


@dataclass
class TrialsSummary:
    n: int
    successes: int
    success_rate: float
    median_dock_time_s: float
    median_lower_bound_s: float
    #: Median over docked trials of each trial's own dock time over its own lower bound.
    median_time_ratio: float
    median_lateral_error_m: float
    p95_lateral_error_m: float
    median_yaw_error_rad: float
    collisions: int
    wall_s: float
    sim_s: float
    controller: str = ""
    world: str = ""
    #: Sim seconds the simulator's clock advanced per wall second while the trials ran (what the whole
    #: stack sustained, waits for late drivers included; NaN when not measured).
    achieved_rtf: float = math.nan
    peak_rss_mb: dict[str, float] = field(default_factory=dict)
    chaos: dict[str, Any] = field(default_factory=dict)

    def headline(self) -> dict[str, Any]:
        keys = ("n", "successes", "success_rate", "median_dock_time_s", "median_lower_bound_s", "median_time_ratio",
                "median_lateral_error_m", "p95_lateral_error_m", "median_yaw_error_rad", "collisions", "wall_s", "sim_s",
                "achieved_rtf")
        return {k: getattr(self, k) for k in keys}


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
    (ax, ay), (bx, by) = segment
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / length2))
    return math.hypot(p[0] - ax - t * dx, p[1] - ay - t * dy)


def trials_stack(options: TrialOptions, endpoint: str, robots: list[str], state_dir: Path | None = None) -> dict[str, Any]:
    """A stack file (as data) with one simulator for all robots and each robot's own services.

    ``state_dir``: where each robot's planner keeps its glass memory and its battery its charge across
    restarts (``--chaos``).
    """
    world = str(options.world)
    py = ["python", "-m"]
    services: dict[str, Any] = {
        "router": {"command": ["zendock", "router", "--listen", endpoint], "restart": "on-failure"},
        "map": {"command": ["zendock", "map", "save", "--world", world, "-o", ".zendock/maps/map.yaml"], "restart": "no"},
        "simulator": {
            "command": [*py, "services.simulator", "--world", world, "-p", f"rtf={options.rtf}",
                        "-p", f"seed={options.seed}", "-p", f"robots={json.dumps(robots)}",
                        "-p", f"localisation_error={json.dumps(list(options.localisation_error))}"],
            "depends_on": {"router": {"condition": "service_started"}},
            "healthcheck": {"liveliness": True, "timeout": "30s"},
            "restart": "on-failure",
        },
    }
    for robot in robots:
        common = {"depends_on": {"router": {"condition": "service_started"}}, "namespace": robot,
                  "restart": "on-failure"}

        def health(node: str) -> dict[str, Any]:
            return {"healthcheck": {"liveliness": node, "timeout": "30s"}}

        keep_charge = ["-p", f"state_file={state_dir / robot / 'battery.json'}"] if state_dir else []
        services[f"battery_{robot}"] = {**common, **health("battery"),
                                        "command": [*py, "services.battery", "-p", "use_sim_time=true", *keep_charge]}
        services[f"pose_{robot}"] = {**common, **health("pose"), "command": [*py, "services.pose", "-p", "use_sim_time=true"]}
        services[f"planner_{robot}"] = {
            **common,
            **health("planner"),
            "command": [*py, "services.planner", "-p", "use_sim_time=true", "-p", "map_yaml=.zendock/maps/map.yaml",
                        *(["-p", f"glass_memory_file={state_dir / robot / 'glass_memory.npz'}"] if state_dir else [])],
            "depends_on": {"router": {"condition": "service_started"},
                           "map": {"condition": "service_completed_successfully"}},
        }
        services[f"docking_{robot}"] = {
            **common,
            **health("docking"),
            "command": [*py, "services.docking", "-p", "use_sim_time=true", "-p", f"dock_database={world}",
                        "-p", f"controller={options.controller}"],
        }
    return {"name": "trials", "namespace": "", "zenoh": {"connect": [endpoint]}, "services": services}


#: How long the harness keeps asking a service that does not answer (it may be restarting: ``--chaos``).
SERVICE_PATIENCE_S = 60.0


def _call_until_answered(session: Any, key: str, srv: Any, request: Any) -> Any:
    """``call_service``, asked again while nothing answers: a killed service is back within seconds, and
    a trial must not fail because the harness asked during those seconds."""
    deadline = time.monotonic() + SERVICE_PATIENCE_S
    while True:
        try:
            return call_service(session, key, srv, request)
        except ServiceUnavailable:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.5)


def _sim_clock(session: Any, robot: str) -> float:
    """The simulator's clock now (sim seconds), NaN when it does not answer."""
    try:
        state = call_service(session, "simulator/state", SIM_STATE, SimStateRequest(robot=robot))
    except ServiceError:
        return math.nan
    return state.stamp.to_sec()


def lower_bounds(world_path: Path, pairs: list[tuple[Pose2D, Pose2D]]) -> list[float]:
    """Shortest collision-free times for ``(start, goal)`` pairs, from the planner's own tool (one process)."""
    if not pairs:
        return []
    lines = "\n".join(json.dumps({"start": list(s.as_tuple()), "goal": list(g.as_tuple())}) for s, g in pairs)
    done = subprocess.run(
        [sys.executable, "-m", "services.planner.lower_bound", "--world", str(world_path), "--batch"],
        input=lines, capture_output=True, text=True, timeout=600, cwd=REPO_ROOT,
    )
    if done.returncode != 0:
        raise RuntimeError(f"lower bounds failed: {done.stderr.strip()[-300:]}")
    return [json.loads(line).get("lower_bound_s", math.nan) for line in done.stdout.strip().splitlines()]


def _run_one(session: Any, robot: str, index: int, start: Pose2D, options: TrialOptions) -> tuple[TrialResult, RunRecord]:
    wall_start = time.monotonic()
    # Full battery first: leaving the dock with the last trial's low charge would trigger docking at
    # the moment of the teleport, before this trial's start is even in place.
    _call_until_answered(session, topic_key(robot, "battery/set_state"), SET_BATTERY_STATE,
                         SetBatteryStateRequest(percentage=1.0, drain_scale=options.drain_scale))
    placed = _call_until_answered(session, "simulator/teleport", TELEPORT, TeleportRequest(*start.as_tuple(), robot=robot))
    if not placed.success:
        raise ServiceError(f"trial {index}: start {start}: {placed.message}")
    observer = RunObserver(session, robot)
    try:
        # The robot may have been charging at the dock a moment ago: start only once the battery has
        # seen it leave, or the old CHARGING would end the new trial at once.
        if not observer.wait(lambda r: bool(r.battery) and not r.last_charging, timeout_s=30.0):
            raise ServiceError(f"trial {index}: the battery still reports charging after the robot left the dock")
        observer.arm()
        _call_until_answered(session, topic_key(robot, "battery/set_state"), SET_BATTERY_STATE,
                             SetBatteryStateRequest(percentage=options.battery_start, drain_scale=options.drain_scale))
        started_sim = None
        deadline_wall = time.monotonic() + options.timeout_sim_s * 3 + 120.0

        def finished(record: RunRecord) -> bool:
            nonlocal started_sim
            if started_sim is None and record.sim_time_s > 0:
                started_sim = record.sim_time_s
            return record.charging or (started_sim is not None and record.sim_time_s - started_sim > options.timeout_sim_s)

        while not observer.wait(finished, timeout_s=1.0) and time.monotonic() < deadline_wall:
            pass
        observer.settle()
        record = observer.snapshot()
    finally:
        observer.close()
    contact = record.contact_at_charging
    trigger = record.trigger_s if record.trigger_s is not None else math.nan
    result = TrialResult(
        index=index,
        robot=robot,
        start=start.as_tuple(),
        docked=bool(record.charging and contact is not None and contact.mated),
        charging=record.charging,
        dock_time_s=(record.charging_s - trigger) if record.charging_s is not None else math.nan,
        lateral_error_m=abs(contact.lateral_error_m) if contact is not None else math.nan,
        yaw_error_rad=abs(contact.yaw_error_rad) if contact is not None else math.nan,
        collisions=record.collisions,
        path_length_m=record.driven_length_m(since_s=record.trigger_s),
        wall_s=time.monotonic() - wall_start,
        sim_s=(record.sim_time_s - trigger) if record.trigger_s is not None else math.nan,
    )
    return result, record


def _percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    if not ordered:
        return math.nan
    return ordered[min(len(ordered) - 1, max(0, math.ceil(q * len(ordered)) - 1))]


def summarise(results: list[TrialResult], wall_s: float, options: TrialOptions, world: World) -> TrialsSummary:
    return summarise_results(results, wall_s, options.controller, world.name)


def summarise_results(results: list[TrialResult], wall_s: float, controller: str, world_name: str) -> TrialsSummary:
    """The summary of any set of trials: one world's, or a campaign's across worlds."""
    ok = [r for r in results if r.docked]
    med = lambda xs: statistics.median(xs) if xs else math.nan  # noqa: E731
    bounded = [r for r in ok if math.isfinite(r.lower_bound_s) and r.lower_bound_s > 0]
    return TrialsSummary(
        n=len(results),
        successes=len(ok),
        success_rate=len(ok) / len(results) if results else math.nan,
        median_dock_time_s=med([r.dock_time_s for r in ok]),
        median_lower_bound_s=med([r.lower_bound_s for r in bounded]),
        median_time_ratio=med([r.dock_time_s / r.lower_bound_s for r in bounded]),
        median_lateral_error_m=med([r.lateral_error_m for r in ok]),
        p95_lateral_error_m=_percentile([r.lateral_error_m for r in ok], 0.95),
        median_yaw_error_rad=med([r.yaw_error_rad for r in ok]),
        collisions=sum(r.collisions for r in results),
        wall_s=wall_s,
        sim_s=sum(r.sim_s for r in results if math.isfinite(r.sim_s)),
        controller=controller,
        world=world_name,
    )


def run_trials(
    options: TrialOptions,
    log: Callable[[str], None] = print,
    progress: Callable[[TrialResult], None] | None = None,
) -> tuple[TrialsSummary, list[TrialResult], Path]:
    """Run every trial; returns the summary, each trial, and the run directory (report, histograms, logs)."""
    world = load_world(options.world)
    if not world.docks:
        raise ValueError(f"{options.world}: the world has no dock")
    run_dir = options.runs_dir / f"trials-{time.strftime('%Y%m%d-%H%M%S')}"
    run_dir.mkdir(parents=True, exist_ok=True)
    workers = max(1, min(options.workers, options.n))
    robots = [f"r{i}" for i in range(workers)]
    starts = reachable_starts(options.world, world, options.n, options.seed)
    endpoint = free_endpoint()
    stack_path = run_dir / "stack.yaml"
    stack_path.write_text(yaml.safe_dump(trials_stack(options, endpoint, robots, run_dir / "state"), sort_keys=False))
    stack = load_stack(stack_path, env={}, project_dir=REPO_ROOT)
    results: list[TrialResult] = []
    records: dict[int, RunRecord] = {}
    errors: list[str] = []
    wall_start = time.monotonic()
    log(f"{options.n} trials in {world.name} with {workers} robot(s), controller {options.controller}, rtf {options.rtf}")
    with Launcher(stack, project_dir=run_dir / "stack", working_dir=REPO_ROOT, project_name="trials") as launcher:
        launcher.wait_healthy(timeout_s=120.0)
        sampler = PeakRssSampler(lambda: [(s.name, s.pid) for s in launcher.ps()])
        todo: queue.Queue[tuple[int, Pose2D]] = queue.Queue()
        for i, start in enumerate(starts):
            todo.put((i, start))
        lock = threading.Lock()
        chaos = ChaosMonkey(launcher, robots, options.chaos_period_s, options.seed) if options.chaos_period_s > 0 else None
        with sampler, open_session(SessionSpec(connect=(endpoint,))) as session, (chaos or _Nothing()):
            clock_start = _sim_clock(session, robots[0])
            wall_clock_start = time.monotonic()

            def worker(robot: str) -> None:
                while True:
                    try:
                        index, start = todo.get_nowait()
                    except queue.Empty:
                        return
                    try:
                        result, record = _run_one(session, robot, index, start, options)
                    except (ServiceError, OSError) as exc:
                        with lock:
                            errors.append(f"trial {index} ({robot}): {exc}")
                        result = TrialResult(index, robot, start.as_tuple(), False, False, math.nan, math.nan,
                                             math.nan, 0, 0.0)
                        record = RunRecord()
                    with lock:
                        results.append(result)
                        records[index] = record
                    if progress is not None:
                        progress(result)

            threads = [threading.Thread(target=worker, args=(robot,), daemon=True) for robot in robots]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            clock_end = _sim_clock(session, robots[0])
            achieved_rtf = (clock_end - clock_start) / max(time.monotonic() - wall_clock_start, 1e-9)
        for status in launcher.ps():
            (run_dir / f"{status.name}.log").write_text("\n".join(launcher.logs(status.name)) + "\n")
    wall_s = time.monotonic() - wall_start
    results.sort(key=lambda r: r.index)
    pairs = []
    for r in results:
        record = records.get(r.index)
        pose = record.pose_at(record.trigger_s) if record is not None and record.trigger_s is not None else None
        pairs.append((pose or Pose2D(*r.start), world.docks[0].pose2d))
    try:
        for r, bound in zip(results, lower_bounds(options.world, pairs)):
            r.lower_bound_s = bound
    except (RuntimeError, subprocess.TimeoutExpired, ValueError) as exc:
        log(f"lower bounds not computed: {exc}")
    summary = summarise(results, wall_s, options, world)
    summary.achieved_rtf = round(achieved_rtf, 2)
    summary.peak_rss_mb = dict(sampler.peak_mb)
    if chaos is not None:
        summary.chaos = chaos.report.summary()
    report = {"summary": asdict(summary), "trials": [asdict(r) for r in results], "errors": errors,
              "options": {k: str(v) for k, v in asdict(options).items()}}
    (run_dir / "trials.json").write_text(json.dumps(report, indent=2) + "\n")
    _histograms(results, run_dir / "histograms.png")
    return summary, results, run_dir


def combine(per_world: list[tuple[TrialsSummary, list[TrialResult]]], controller: str) -> TrialsSummary:
    """One summary over several worlds' trials: medians over every trial, not medians of medians."""
    results = [r for _, rs in per_world for r in rs]
    wall_s = sum(s.wall_s for s, _ in per_world)
    summary = summarise_results(results, wall_s, controller, ", ".join(s.world for s, _ in per_world))
    rates = [(s.achieved_rtf, s.wall_s) for s, _ in per_world if math.isfinite(s.achieved_rtf)]
    if rates:  # weighted by each world's wall time: the rate of the campaign as a whole
        summary.achieved_rtf = round(sum(r * w for r, w in rates) / max(sum(w for _, w in rates), 1e-9), 2)
    for s, _ in per_world:
        for name, mb in s.peak_rss_mb.items():
            summary.peak_rss_mb[name] = max(mb, summary.peak_rss_mb.get(name, 0.0))
    chaos = [s.chaos for s, _ in per_world if s.chaos]
    if chaos:
        summary.chaos = _combine_chaos(chaos)
    return summary


def _combine_chaos(reports: list[dict[str, Any]]) -> dict[str, Any]:
    recovery = [t for report in reports for t in report.get("recovery_s", [])]
    return {
        "kills": sum(r["kills"] for r in reports),
        "recovered": sum(r["recovered"] for r in reports),
        "median_recovery_s": round(statistics.median(recovery), 2) if recovery else math.nan,
        "max_recovery_s": round(max(recovery), 2) if recovery else math.nan,
        "killed": [name for r in reports for name in r.get("killed", [])],
        "recovery_s": recovery,
    }


class _Nothing:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


def _histograms(results: list[TrialResult], path: Path) -> None:
    import matplotlib  # noqa: PLC0415 - slow to import; only when writing pictures

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    ok = [r for r in results if r.docked]
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    panels = [
        ("dock time (s, sim)", [r.dock_time_s for r in ok], "#4472c4"),
        ("lateral error at contact (mm)", [1000 * r.lateral_error_m for r in ok], "#ed7d31"),
        ("yaw error at contact (deg)", [math.degrees(r.yaw_error_rad) for r in ok], "#70ad47"),
    ]
    for ax, (title, values, colour) in zip(axes, panels):
        if values:
            ax.hist(values, bins=min(30, max(5, len(values) // 3)), color=colour, edgecolor="white")
        ax.set_title(title)
        ax.set_ylabel("trials")
    fig.suptitle(f"{len(ok)}/{len(results)} docked")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
