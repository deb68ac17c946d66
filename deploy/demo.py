"""``zendock demo``: the whole system once, start to charge, measured on ground truth.

It brings the default stack up through the launcher (embedded router on a free loopback port, so it
never meets another stack), optionally places the robot, sets the battery just above the low
threshold so it soon crosses it, and waits for ``CHARGING``. Then it writes ``runs/<timestamp>/``:
``report.json``, ``trajectory.png`` and the services' logs, prints a short report and brings the
stack down. Exit 0 only when the robot docked and charges.
"""

from __future__ import annotations

import contextlib
import json
import math
import subprocess
import time
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from deploy import strict_json
from deploy.glass_report import GlassMarks, read_glass_marks
from deploy.launcher import Launcher, free_endpoint, load_stack
from deploy.launcher.overrides import with_params
from deploy.memory import PeakRssSampler
from deploy.observer import RunObserver, RunRecord
from deploy.paths import REPO_ROOT, RUNS_DIR, new_run_dir
from deploy.progress import TERMINAL_PERIOD_S, Throttle, demo_line
from deploy.replacements import Replacement, apply_replacements, replacements_report
from deploy.service_tools import run_tool
from shared.controllers import DEFAULT_CONTROLLER, ControllerName, DetectorName
from shared.geometry import Pose2D
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest
from shared.interfaces.simulator import TELEPORT, TeleportRequest
from shared.messages import String
from shared.names import topic_key
from shared.node import ServiceError, call_service
from shared.schema import MessageError
from shared.session import SessionSpec, open_session
from shared.world import World, load_world

DEFAULT_STACK = REPO_ROOT / "deploy" / "stack.yaml"
DEFAULT_WORLD = REPO_ROOT / "deploy" / "worlds" / "seed_room.yaml"
DOCK_SERVICES = ("router", "map", "simulator", "perception", "battery", "pose", "planner", "docking")
#: Where the docking service says which phase it is in (std_msgs/String).
DOCKING_STATE = "docking/state"
#: With ``--compose`` the robot's services run as one process, the group ``robot`` (zendock container).
ROBOT_GROUP = {"robot": ["perception", "battery", "pose", "planner", "docking"]}


@dataclass(frozen=True)
class DemoOptions:
    world: Path = DEFAULT_WORLD
    controller: ControllerName = DEFAULT_CONTROLLER
    #: aruco: the dock is found in camera images by the perception service; synthetic: the simulator's truth
    detector: DetectorName = "aruco"
    rtf: str = "1.0"
    seed: int = 0
    start: tuple[float, float, float] | None = None
    timeout_sim_s: float = 300.0
    battery_start: float = 0.26
    drain_scale: float = 20.0
    #: The charge fills this many times faster, and the run goes on ``charging_shown_s`` of sim time past
    #: CHARGING: the picture shows the charge rise (at 1x, 5 s on the dock add 0.07 %).
    charge_scale: float = 60.0
    charging_shown_s: float = 5.0
    runs_dir: Path = RUNS_DIR
    #: map->odom error of the simulated localisation (x_m, y_m, yaw_rad); trials turn it on.
    localisation_error: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: The robot's services in one process (``zendock container``) instead of one process each.
    compose: bool = False
    #: ``--service NAME=COMMAND``: a user's program in place of zendock's service (:mod:`deploy.replacements`).
    replacements: tuple[Replacement, ...] = ()


@dataclass
class DemoReport:
    docked: bool
    charging: bool
    controller: ControllerName
    world: str
    dock_time_s: float
    final_lateral_error_m: float
    final_yaw_error_rad: float
    collisions: int
    path_length_m: float
    lower_bound_s: float
    #: Recoveries navigation began during the run (each marked on the picture).
    recoveries: int = 0
    #: Why there is no lower bound ("" when there is one).
    lower_bound_s_reason: str = ""
    #: The narrowest gap on the widest way to the dock, glass solid (the lower-bound tool's; NaN: no bound).
    way_width_m: float = math.nan
    #: The planner's glass memory at the end, against the world's panes (see :mod:`deploy.glass_report`).
    false_glass_cells: float = math.nan
    glass_coverage: float = math.nan
    wall_s: float = 0.0
    sim_s: float = 0.0
    trigger_s: float = 0.0
    #: Ground-truth speed as the contacts mated; above the contact speed limit the robot has not docked.
    arrival_speed_mps: float = math.nan
    peak_rss_mb: dict[str, float] = field(default_factory=dict)
    #: Each replaced service and the command that ran in its place (``--service``).
    replaced_services: dict[str, str] = field(default_factory=dict)
    run_dir: str = ""

    def as_dict(self) -> dict[str, Any]:
        """The report's fields; a count is an integer, an empty reason is left out (a measure that is missing
        is NaN here, ``null`` with its reason once :mod:`deploy.strict_json` writes it)."""
        out = asdict(self)
        if math.isfinite(self.false_glass_cells):
            out["false_glass_cells"] = int(self.false_glass_cells)
        if not self.lower_bound_s_reason:
            del out["lower_bound_s_reason"]
        return out


def lower_bound(world_path: Path, start: Pose2D, goal: Pose2D) -> dict[str, float]:
    """The shortest collision-free time from ``start`` to ``goal``, computed by the planner's own tool.

    Run as a process (``python -m services.planner.lower_bound``) so the launcher floor stays apart
    from the services' code.
    """
    done = run_tool(
        "services.planner.lower_bound",
        [
            "--world",
            str(world_path),
            "--start",
            *map(str, start.as_tuple()),
            "--goal",
            *map(str, goal.as_tuple()),
        ],
        timeout_s=120.0,
    )
    try:
        return dict(done.last_json())
    except RuntimeError as exc:
        raise RuntimeError(f"lower bound failed: {exc}") from None


#: The file in a run directory while the demo has not written its report.
INCOMPLETE_MARK = "INCOMPLETE"


def stack_environment(options: DemoOptions, endpoint: str, run_dir: Path) -> dict[str, str]:
    return {
        "ZENOH_LISTEN": endpoint,
        "ZENOH_CONNECT": endpoint,
        "ZENDOCK_WORLD": str(options.world),
        "ZENDOCK_DETECTOR": options.detector,
        "ZENDOCK_RTF": options.rtf,
        "ZENDOCK_SEED": str(options.seed),
        "ZENDOCK_LOCALISATION_ERROR": json.dumps(list(options.localisation_error)),
        "ZENDOCK_GLASS_MEMORY": str(run_dir / "glass_memory.npz"),
        # the run's own map: two demos (or a demo and a test) in one checkout never read each other's
        "ZENDOCK_MAP": str(run_dir / "map.yaml"),
    }


def build_report(
    record: RunRecord, options: DemoOptions, world: World, wall_s: float, bound_s: float
) -> DemoReport:
    outcome = record.outcome()
    return DemoReport(
        docked=outcome.docked,
        charging=outcome.charging,
        controller=options.controller,
        world=world.name,
        dock_time_s=outcome.dock_time_s,
        final_lateral_error_m=outcome.lateral_error_m,
        final_yaw_error_rad=outcome.yaw_error_rad,
        collisions=outcome.collisions,
        path_length_m=outcome.path_length_m,
        lower_bound_s=bound_s,
        recoveries=len(record.recovery_points),
        wall_s=wall_s,
        sim_s=record.sim_time_s,
        trigger_s=outcome.trigger_s,
        arrival_speed_mps=record.arrival_speed_mps,
    )


def robot_group(replaced: Iterable[str] = ()) -> dict[str, list[str]]:
    """The ``--compose`` group without the services a user replaced: those run as their own processes."""
    return {group: [m for m in members if m not in set(replaced)] for group, members in ROBOT_GROUP.items()}


def _composed(names: tuple[str, ...], group: dict[str, list[str]]) -> tuple[str, ...]:
    grouped = {m for members in group.values() for m in members}
    return (*(n for n in names if n not in grouped), *group)


def _status_line(record: RunRecord, world: World, docking_state: str, trigger_below: float) -> str:
    """The demo's progress now: the battery before the trigger, the docking state and distance after."""
    battery = record.battery[-1][1] if record.battery else None
    distance = None
    if record.driven and world.docks:
        _, x, y, _ = record.driven[-1]
        dock = world.docks[0].pose2d
        distance = math.hypot(dock.x - x, dock.y - y)
    return demo_line(
        sim_s=record.sim_time_s,
        battery=battery,
        trigger_s=record.trigger_s,
        docking_state=docking_state,
        distance_m=distance,
        trigger_below=trigger_below,
    )


def run_demo(
    options: DemoOptions,
    log: Any = print,
    status: Callable[[str], None] | None = None,
    status_period_s: float = TERMINAL_PERIOD_S,
) -> DemoReport:
    """Bring the stack up, dock once, write the run's files; always brings the stack down.

    ``status`` gets a progress line (battery, then docking state and distance to the dock, sim time) at
    every phase change and at most every ``status_period_s`` wall seconds otherwise.
    """
    world = load_world(options.world)
    run_dir = new_run_dir(options.runs_dir)
    # Until the report is written the run is marked incomplete: an interrupted or failed demo leaves no
    # directory that looks like a finished run.
    (run_dir / INCOMPLETE_MARK).write_text(
        "this demo did not finish (interrupted, or it failed before its report): no report.json\n"
    )
    endpoint = free_endpoint()
    group = robot_group(r.name for r in options.replacements)
    stack = load_stack(
        DEFAULT_STACK,
        env=stack_environment(options, endpoint, run_dir),
        project_dir=REPO_ROOT,
        compose=group if options.compose else None,
    )
    stack = apply_replacements(
        with_params(stack, "docking", {"controller": options.controller}), options.replacements
    )
    services = _composed(DOCK_SERVICES, group) if options.compose else DOCK_SERVICES
    wall_start = time.monotonic()
    log(
        f"stack on {endpoint}: world {world.name}, controller {options.controller}, rtf {options.rtf}"
        + "".join(f", {r.name} replaced by `{r.command}`" for r in options.replacements)
    )
    with Launcher(
        stack, services=services, project_dir=run_dir / "stack", working_dir=REPO_ROOT, project_name="demo"
    ) as launcher:
        launcher.wait_healthy(timeout_s=90.0)
        sampler = PeakRssSampler(lambda: [(s.name, s.pid) for s in launcher.ps()])
        with sampler, open_session(SessionSpec(connect=(endpoint,))) as session:
            observer = RunObserver(session)
            docking_state = [""]

            def on_docking_state(sample: Any) -> None:
                with contextlib.suppress(MessageError):
                    docking_state[0] = String.decode(sample.payload.to_bytes()).data

            state_sub = session.declare_subscriber(topic_key("", DOCKING_STATE), on_docking_state)
            throttle = Throttle(status_period_s)
            phase_shown: list[object] = []

            def show_status() -> None:
                record = observer.snapshot()
                phase = (record.trigger_s is None, docking_state[0])
                if status is not None and (throttle.due(time.monotonic()) or phase_shown[-1:] != [phase]):
                    phase_shown[:] = [phase]
                    status(_status_line(record, world, docking_state[0], observer.low_threshold))

            try:
                if options.start is not None:
                    placed = call_service(
                        session,
                        topic_key("", "simulator/teleport"),
                        TELEPORT,
                        TeleportRequest(*options.start),
                    )
                    if not placed.success:
                        raise ServiceError(f"--start {options.start}: {placed.message}")
                observer.arm()
                battery_set_s = observer.sim_time()
                call_service(
                    session,
                    "battery/set_state",
                    SET_BATTERY_STATE,
                    SetBatteryStateRequest(
                        percentage=options.battery_start,
                        drain_scale=options.drain_scale,
                        charge_scale=options.charge_scale,
                    ),
                )
                log(
                    f"battery set to {options.battery_start:.0%}; waiting for the low-battery trigger and CHARGING"
                )
                deadline_wall = time.monotonic() + options.timeout_sim_s * 4 + 60.0

                def finished(record: RunRecord) -> bool:
                    too_late = (
                        record.trigger_s is not None
                        and record.sim_time_s - record.trigger_s > options.timeout_sim_s
                    )
                    return record.charging or too_late or record.sim_time_s > options.timeout_sim_s + 60.0

                while not observer.wait(finished, timeout_s=0.5):
                    show_status()
                    if time.monotonic() > deadline_wall:
                        log("wall-clock limit reached")
                        break
                observer.settle()
                charged_from = observer.snapshot().charging_s
                if charged_from is not None:  # a little more, for the picture: the charge rising
                    observer.wait(
                        lambda r: r.sim_time_s >= charged_from + options.charging_shown_s,
                        timeout_s=options.charging_shown_s * 4 + 10.0,
                    )
                record = observer.snapshot()
            finally:
                state_sub.undeclare()
                observer.close()
        for name in services:
            (run_dir / f"{name}.log").write_text("\n".join(launcher.logs(name)) + "\n")
    wall_s = time.monotonic() - wall_start
    start_pose = record.pose_at(record.trigger_s) if record.trigger_s is not None else None
    bound_s, bound_reason = math.nan, "the run never triggered docking" if start_pose is None else "no dock"
    way_width_m = math.nan
    if start_pose is not None and world.docks:
        try:
            answer = lower_bound(options.world, start_pose, world.docks[0].pose2d)
            bound_s = float(answer["lower_bound_s"]) if answer.get("lower_bound_s") is not None else math.nan
            bound_reason = str(answer.get("error", ""))
            way_width_m = float(answer.get("way_width_m", math.nan))
        except (RuntimeError, subprocess.TimeoutExpired, ValueError) as exc:
            bound_reason = f"lower bound not computed: {exc}"
            log(bound_reason)
    report = build_report(record, options, world, wall_s, bound_s)
    report.lower_bound_s_reason = "" if math.isfinite(bound_s) else bound_reason
    report.way_width_m = way_width_m
    glass = read_glass_marks(run_dir / "glass_memory.npz", world)
    if glass is not None:
        counted = glass.report()
        report.false_glass_cells, report.glass_coverage = (
            float(counted.false_glass_cells),
            counted.glass_coverage,
        )
    report.run_dir = str(run_dir)
    report.peak_rss_mb = dict(sampler.peak_mb)
    report.replaced_services = replacements_report(options.replacements)
    (run_dir / "report.json").write_text(strict_json.dumps(report.as_dict(), indent=2) + "\n")
    _plot(
        world,
        record,
        run_dir / "trajectory.png",
        log,
        glass,
        battery_set=(battery_set_s, options.battery_start),
    )
    (run_dir / INCOMPLETE_MARK).unlink()
    return report


def _plot(
    world: World,
    record: RunRecord,
    path: Path,
    log: Any,
    glass: GlassMarks | None = None,
    battery_set: tuple[float, float] | None = None,
) -> None:
    """The run's picture; ``battery_set`` ``(sim_s, percentage)``: when and to what the demo set the charge."""
    try:
        from deploy.plotting import plot_run  # noqa: PLC0415 - matplotlib is slow to import
    except ImportError:
        log("plotting is not available; no trajectory picture")
        return
    track = record.timed_track_since_placed()
    plot_run(
        world,
        path,
        driven=[(x, y) for _, x, y in track],
        driven_times_s=[t for t, _, _ in track],
        plans=record.plans,
        sonar_echoes=record.sonar_echoes,
        collisions=record.collision_points,
        recoveries=record.recovery_points,
        glass_marks=glass.true_xy if glass is not None else (),
        false_glass_marks=glass.false_xy if glass is not None else (),
        battery=record.battery,
        battery_set=battery_set,
        events=[
            (t_s, label)
            for t_s, label in ((record.trigger_s, "docking triggered"), (record.charging_s, "CHARGING"))
            if t_s is not None
        ],
    )
