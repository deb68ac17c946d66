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
import subprocess
import threading
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

import yaml
import zenoh

from deploy import strict_json
from deploy.glass_report import read_glass_marks
from deploy.launcher import Launcher, free_endpoint
from deploy.memory import PeakRssSampler
from deploy.observer import RunObserver, RunRecord
from deploy.paths import REPO_ROOT, new_run_dir
from deploy.trials.chaos import ChaosMonkey
from deploy.trials.glass_clearance import closest_glass_pass
from deploy.trials.records import TrialOptions, TrialResult, TrialsSummary
from deploy.trials.stack import GLASS_MEMORY_FILE, trials_stack
from deploy.trials.starts import beacon_starts, lower_bound_parts, reachable_starts
from deploy.trials.summary import summarise, summary_reasons
from deploy.trials.time_over_bound import GlassSlowing, time_over_bound
from shared import topics
from shared.geometry import Pose2D
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest
from shared.interfaces.simulator import SIM_STATE, TELEPORT, SimStateRequest, TeleportRequest
from shared.names import stats_key, topic_key
from shared.node import ServiceError, ServiceUnavailable, call_service
from shared.session import SessionSpec, open_session
from shared.world import World, load_world

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


def _node_stats(session: Any, namespace: str, node: str, names: tuple[str, ...]) -> tuple[float, ...]:
    """Counters a node adds to its stats (``extra``), each NaN when the node does not answer or has not that
    one (a service replaced by one that does not count it)."""
    try:
        for reply in session.get(stats_key(namespace, node), timeout=2.0):
            if reply.ok is not None:
                extra = json.loads(reply.ok.payload.to_bytes()).get("extra", {})
                values = [extra.get(name) if isinstance(extra, dict) else None for name in names]
                return tuple(float(v) if isinstance(v, (int, float)) else math.nan for v in values)
    except (zenoh.ZError, ValueError):
        pass
    return tuple(math.nan for _ in names)


def _glass_slowing(session: Any, namespace: str) -> GlassSlowing:
    """The planner's count of its driving under a glass speed limit so far (NaN where it does not count)."""
    seconds, metres = _node_stats(
        session, namespace, "planner", (topics.GLASS_SLOWED_STAT, topics.GLASS_SLOWED_M_STAT)
    )
    return GlassSlowing(seconds, metres)


def _run_one(
    session: Any, robot: str, index: int, start: Pose2D, options: TrialOptions, world: World, state_dir: Path
) -> tuple[TrialResult, RunRecord]:
    wall_start = time.monotonic()
    # Full battery first: leaving the dock with the last trial's low charge would trigger docking at
    # the moment of the teleport, before this trial's start is even in place.
    _call_until_answered(
        session,
        topic_key(robot, "battery/set_state"),
        SET_BATTERY_STATE,
        SetBatteryStateRequest(percentage=1.0, drain_scale=options.drain_scale),
    )
    placed = _call_until_answered(
        session, "simulator/teleport", TELEPORT, TeleportRequest(*start.as_tuple(), robot=robot)
    )
    if not placed.success:
        raise ServiceError(f"trial {index}: start {start}: {placed.message}")
    observer = RunObserver(session, robot)
    try:
        # The robot may have been charging at the dock a moment ago: start only once the battery has
        # seen it leave, or the old CHARGING would end the new trial at once.
        if not observer.wait(lambda r: bool(r.battery) and not r.last_charging, timeout_s=30.0):
            raise ServiceError(
                f"trial {index}: the battery still reports charging after the robot left the dock"
            )
        observer.arm()
        glass_before = _glass_slowing(session, robot)
        _call_until_answered(
            session,
            topic_key(robot, "battery/set_state"),
            SET_BATTERY_STATE,
            SetBatteryStateRequest(percentage=options.battery_start, drain_scale=options.drain_scale),
        )
        started_sim = None
        deadline_wall = time.monotonic() + options.timeout_sim_s * 3 + 120.0

        def finished(record: RunRecord) -> bool:
            nonlocal started_sim
            if started_sim is None and record.sim_time_s > 0:
                started_sim = record.sim_time_s
            return record.charging or (
                started_sim is not None and record.sim_time_s - started_sim > options.timeout_sim_s
            )

        while not observer.wait(finished, timeout_s=1.0) and time.monotonic() < deadline_wall:
            pass
        observer.settle()
        record = observer.snapshot()
    finally:
        observer.close()
    glass_after = _glass_slowing(session, robot)
    glass_slowed_s = glass_after.seconds - glass_before.seconds
    glass_slowed_m = glass_after.metres - glass_before.metres
    outcome = record.outcome()
    result = TrialResult(
        index=index,
        robot=robot,
        start=start.as_tuple(),
        docked=outcome.docked,
        charging=outcome.charging,
        dock_time_s=outcome.dock_time_s,
        lateral_error_m=outcome.lateral_error_m,
        yaw_error_rad=outcome.yaw_error_rad,
        collisions=outcome.collisions,
        path_length_m=outcome.path_length_m,
        wall_s=time.monotonic() - wall_start,
        sim_s=record.sim_time_s - outcome.trigger_s,
        phase_s=record.phase_durations(),
        arrival_speed_mps=record.arrival_speed_mps,
        too_fast=outcome.too_fast,
        glass_slowed_s=round(glass_slowed_s, 3) if math.isfinite(glass_slowed_s) else math.nan,
        glass_slowed_m=round(glass_slowed_m, 3) if math.isfinite(glass_slowed_m) else math.nan,
        collided=[
            {"kind": kind, "x": round(x, 3), "y": round(y, 3)}
            for kind, (x, y) in zip(record.collision_kinds, record.collision_points, strict=True)
        ],
    )
    closest = closest_glass_pass(world, record.driven)
    if closest is not None:
        result.glass_clearance_m = round(closest.clearance_m, 4)
        if math.isfinite(closest.x):
            result.glass_closest_xy = [round(closest.x, 3), round(closest.y, 3)]
    # The planner writes its glass memory at most once a second: this is it within a second of the end.
    glass = read_glass_marks(state_dir / robot / GLASS_MEMORY_FILE, world)
    if glass is not None:
        counted = glass.report(record.sonar_echoes)
        result.false_glass_cells, result.glass_coverage = (
            float(counted.false_glass_cells),
            counted.glass_coverage,
        )
        result.panes_heard, result.panes_found = counted.panes_heard, counted.panes_found
    return result, record


class _Nothing:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


def run_trials(
    options: TrialOptions,
    log: Callable[[str], None] = print,
    progress: Callable[[TrialResult], None] | None = None,
    tap: Callable[
        [Any, list[str], Callable[[], list[tuple[str, int | None]]], str], AbstractContextManager[Any]
    ]
    | None = None,
) -> tuple[TrialsSummary, list[TrialResult], Path]:
    """Run every trial; returns the summary, each trial, and the run directory (report, histograms, logs).

    ``tap(session, robots, processes, endpoint)``, when given, is entered once the stack is healthy and left after the
    last trial, before the stack goes down: a benchmark's way to watch the campaign's bus (``zendock bench messages``,
    ``zendock bench record``); ``endpoint`` is the campaign's router.
    """
    world = load_world(options.world)
    if not world.docks:
        raise ValueError(f"{options.world}: the world has no dock")
    shard = f"-shard{options.shard.index}of{options.shard.count}" if options.shard.count > 1 else ""
    run_dir = new_run_dir(options.runs_dir, "trials-", f"-{options.world.stem}{shard}")
    if options.starts == "beacon":
        starts = beacon_starts(world, options.n, options.seed)
    else:
        starts = reachable_starts(options.world, world, options.n, options.seed)
    # The whole campaign's starts, then this shard's slice of them, keeping the campaign's trial indices.
    mine = options.shard.select(starts)
    if not mine:
        raise ValueError(f"shard {options.shard} of {options.n} trials has no trial")
    workers = max(1, min(options.workers, len(mine)))
    robots = [f"r{i}" for i in range(workers)]
    endpoint = free_endpoint()
    stack = trials_stack(options, endpoint, robots, run_dir / "state")
    # The run's record of what ran (as ``zendock config`` prints a stack), not read back.
    (run_dir / "stack.yaml").write_text(yaml.safe_dump(stack.to_dict(), sort_keys=False))
    results: list[TrialResult] = []
    records: dict[int, RunRecord] = {}
    errors: list[str] = []
    wall_start = time.monotonic()
    sharded = f" (shard {options.shard}: {len(mine)} of {options.n})" if options.shard.count > 1 else ""
    log(
        f"{options.n} trials{sharded} in {world.name} with {workers} robot(s), controller {options.controller}, "
        f"detector {options.detector}, {options.starts} starts, rtf {options.rtf}"
        + "".join(f", {r.name} replaced by `{r.command}`" for r in options.replacements)
    )
    with Launcher(
        stack,
        project_dir=run_dir / "stack",
        working_dir=REPO_ROOT,
        project_name="trials",
        standby=options.standby,
    ) as launcher:
        launcher.wait_healthy(timeout_s=120.0)
        log(f"stack healthy after {time.monotonic() - wall_start:.0f} s; docking")

        def processes() -> list[tuple[str, int | None]]:
            return [(s.name, s.pid) for s in launcher.ps()]

        sampler = PeakRssSampler(processes)
        todo: queue.Queue[tuple[int, Pose2D]] = queue.Queue()
        for i, start in mine:
            todo.put((i, start))
        lock = threading.Lock()
        chaos = (
            ChaosMonkey(launcher, robots, options.chaos_period_s, options.seed)
            if options.chaos_period_s > 0
            else None
        )
        with (
            sampler,
            open_session(SessionSpec(connect=(endpoint,))) as session,
            chaos or _Nothing(),
            tap(session, robots, processes, endpoint) if tap is not None else _Nothing(),
        ):
            clock_start = _sim_clock(session, robots[0])
            wall_clock_start = time.monotonic()
            sampler.sample()
            cpu_start = sampler.cpu_s

            def worker(robot: str) -> None:
                while True:
                    try:
                        index, start = todo.get_nowait()
                    except queue.Empty:
                        return
                    try:
                        result, record = _run_one(
                            session, robot, index, start, options, world, run_dir / "state"
                        )
                    except (ServiceError, OSError) as exc:
                        with lock:
                            errors.append(f"trial {index} ({robot}): {exc}")
                        result = TrialResult(
                            index, robot, start.as_tuple(), False, False, math.nan, math.nan, math.nan, 0, 0.0
                        )
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
            sampler.sample()
            cpu_per_sim_s = {
                name: round((seconds - cpu_start.get(name, 0.0)) / max(clock_end - clock_start, 1e-9), 4)
                for name, seconds in sorted(sampler.cpu_s.items())
            }
        for status in launcher.ps():
            (run_dir / f"{status.name}.log").write_text("\n".join(launcher.logs(status.name)) + "\n")
    wall_s = time.monotonic() - wall_start
    results.sort(key=lambda r: r.index)
    pairs = []
    for r in results:
        record = records.get(r.index)
        pose = (
            record.pose_at(record.trigger_s) if record is not None and record.trigger_s is not None else None
        )
        pairs.append((pose or Pose2D(*r.start), world.docks[0].pose2d))
    try:
        for r, bound in zip(results, lower_bound_parts(options.world, pairs)):
            r.lower_bound_s = bound.seconds
            r.way_width_m = bound.way_width_m
            record = records.get(r.index)
            if record is not None and r.charging:
                glass = GlassSlowing(r.glass_slowed_s, r.glass_slowed_m)
                r.over_bound_s = time_over_bound(r.phase_s, record.phase_lengths_m(), bound, glass)
    except (RuntimeError, subprocess.TimeoutExpired, ValueError) as exc:
        errors.append(f"lower bounds not computed: {exc}")
        log(errors[-1])
    summary = summarise(results, wall_s, options, world)
    summary.achieved_rtf = round(achieved_rtf, 2)
    summary.peak_rss_mb = dict(sampler.peak_mb)
    summary.cpu_s_per_sim_s = cpu_per_sim_s
    if chaos is not None:
        summary.chaos = chaos.report.summary()
    report = {
        "summary": asdict(summary),
        "trials": [asdict(r) for r in results],
        "errors": errors,
        "options": {f.name: str(getattr(options, f.name)) for f in fields(options)},
    }
    (run_dir / "trials.json").write_text(strict_json.dumps(report, summary_reasons(summary), indent=2) + "\n")
    from deploy.plotting import plot_trial_histograms  # noqa: PLC0415 - matplotlib is slow to import

    plot_trial_histograms(results, run_dir / "histograms.png")
    return summary, results, run_dir
