"""``zendock bench ...``: measurements, not tests. Each prints a table, or JSON with ``--json``."""

from __future__ import annotations

import argparse
import json
import sys

from rich.console import Console
from rich.table import Table

from deploy import strict_json
from deploy.arg_types import count, real_time_factor
from deploy.options import add_detector_option
from deploy.service_tools import run_tool
from deploy.world_names import world_argument, world_file_argument


def _print(result: dict, as_json: bool, title: str) -> None:
    if as_json:
        print(json.dumps(result))
        return
    table = Table(title=title)
    table.add_column("metric")
    table.add_column("value", justify="right")
    for key, value in result.items():
        table.add_row(key, f"{value}")
    Console().print(table)


def _bench_bus(args: argparse.Namespace) -> int:
    from deploy.bench.bus import run_bus_bench  # noqa: PLC0415 - opens Zenoh sessions: only this verb needs it

    try:
        result = run_bus_bench(rounds=args.rounds)
    except (RuntimeError, ValueError) as exc:
        print(f"zendock bench bus: {exc}", file=sys.stderr)
        return 1
    _print(result.as_dict(), args.json, "bus round trip: zendock typed vs raw zenoh-python")
    return 0


def _tool_json(command: str, module: str, argv: list[str], timeout_s: float = 600.0) -> dict | None:
    """Run a service's benchmark as a process (the launcher floor never imports service code)."""
    try:
        return run_tool(module, argv, timeout_s=timeout_s).last_json()
    except (RuntimeError, ValueError) as exc:
        print(f"zendock bench {command}: {exc}", file=sys.stderr)
        return None


def _bench_sim(args: argparse.Namespace) -> int:
    result = _tool_json("sim", "services.simulator.bench", [args.world, str(args.seconds)])
    if result is None:
        return 1
    _print(result, args.json, "simulator throughput (all sensors on, no bus)")
    return 0


def _bench_docking(args: argparse.Namespace) -> int:
    argv = ["--json", "--latency", str(args.latency), "--seed", str(args.seed)]
    report = _tool_json("docking", "services.docking.bench", argv)
    if report is None:
        return 1
    summary = {
        f"{name} {key}": value
        for name, row in report.get("controllers", {}).items()
        for key, value in row.items()
        if isinstance(value, (int, float, str))
    }
    _print(
        summary or report, args.json, "final approach on the kinematic model: seed vs Nav2 defaults vs tuned"
    )
    return 0


def _bench_ir(args: argparse.Namespace) -> int:
    argv = ["--json", "--n", str(args.n), "--seed", str(args.seed)]
    for world in args.world or ["deploy/worlds/unseen"]:
        argv += ["--world", world]
    report = _tool_json("ir", "services.docking.ir_bench", argv, timeout_s=3600.0)
    if report is None:
        return 1
    if args.json:
        print(strict_json.dumps(report))
        return 0
    table = Table(title="infrared docking from beacon starts, kinematic model with the simulator's beacon")
    for column in (
        "world",
        "docked",
        "collisions",
        "time median",
        "time p95",
        "lateral median",
        "lateral p95",
    ):
        table.add_column(column, justify="right")
    for name, row in {**report["worlds"], "all": report["summary"]}.items():
        table.add_row(
            name,
            f"{row['docked']}/{row['n']}",
            str(row["collisions"]),
            f"{row['median_time_s']} s",
            f"{row['p95_time_s']} s",
            f"{row['median_lateral_error_m']} m",
            f"{row['p95_lateral_error_m']} m",
        )
    Console().print(table)
    for failure in report["failures"]:
        print(
            f"failed from {tuple(round(v, 2) for v in failure['start'])}: {failure['outcome']}; last states "
            f"{' > '.join(failure['states'][-8:])}"
        )
    return 0


def _bench_planner(args: argparse.Namespace) -> int:
    planning = _tool_json(
        "planner",
        "services.planner.bench",
        ["--repeats", str(args.repeats), "--resolution", str(args.resolution)],
    )
    if planning is None:
        return 1
    result: dict = dict(planning)
    if not args.planning_only:
        from deploy.bench.navigation import run_navigation_bench  # noqa: PLC0415 - starts a stack

        try:
            routes = run_navigation_bench(rtf=args.rtf, timeout_s=args.timeout)
        except RuntimeError as exc:
            print(f"zendock bench planner: {exc}", file=sys.stderr)
            return 1
        for i, route in enumerate(routes):
            x, y, _ = route.goal
            label = f"{route.world}[{i}] ({route.start.x:.1f},{route.start.y:.1f})->({x:.1f},{y:.1f})"
            result.update({f"{label} {key}": value for key, value in route.as_dict().items()})
    _print(result, args.json, "planner: planning time on a 20 m x 20 m room, time to goal in the simulator")
    return 0


def _bench_perception(args: argparse.Namespace) -> int:
    from deploy.bench.perception import run_perception_bench  # noqa: PLC0415 - starts a stack

    try:
        report = run_perception_bench(frames_per_point=args.frames)
    except RuntimeError as exc:
        print(f"zendock bench perception: {exc}", file=sys.stderr)
        return 1
    if args.json:
        print(strict_json.dumps(report))
        return 0
    table = Table(
        title=f"dock from pixels: detection rate and error by distance (angles {report['angles_deg']} deg)"
    )
    for column in ("distance", "detected", "position median", "position p95", "yaw median"):
        table.add_column(column, justify="right")
    for distance, row in report["by_range"].items():
        table.add_row(
            distance,
            f"{100 * row['detection_rate']:.0f} %",
            f"{row['median_position_error_mm']} mm",
            f"{row['p95_position_error_mm']} mm",
            f"{row['median_yaw_error_deg']} deg",
        )
    Console().print(table)
    print(
        f"all viewpoints: {100 * report['detection_rate']:.1f} % of frames; image to dock pose "
        f"{report['median_latency_ms']} ms (median); render {report['render_ms_per_frame']} ms per frame; "
        f"perception {report['perception_cpu_ms_per_frame']} ms CPU per frame"
    )
    return 0


def _print_dds(dds: dict) -> None:
    """The DDS face (real rclpy on Fast DDS) beside rclpy-to-rclpy, measured in the same run."""
    table = Table(title="DDS face (rclpy, Fast DDS): through the face against rclpy-to-rclpy, same run")
    for column in ("measure", "p50", "p90"):
        table.add_column(column, justify="right")
    rows = [
        ("cmd_vel -> odom, through the face", dds["cmd_vel_odom_round_trip"]["through_face"]),
        ("cmd_vel -> odom, zendock direct", dds["cmd_vel_odom_round_trip"]["zendock_direct"]),
        ("round trip rclpy -> rclpy", dds["cmd_vel_odom_round_trip"]["rclpy_to_rclpy"]),
        ("battery_status: added by the face", dds["battery_status_latency"]["added_by_face"]),
        ("BatteryState rclpy -> rclpy, one way", dds["battery_status_latency"]["rclpy_to_rclpy_one_way"]),
    ]
    for label, stats in rows:
        table.add_row(label, f"{stats.get('p50_ms', 'n/a')} ms", f"{stats.get('p90_ms', 'n/a')} ms")
    Console().print(table)
    face = dds["face"]
    print(
        f"DDS face: idle {face['idle']['cpu_percent']} % CPU, {face['idle']['rss_mb']} MB; forwarding the sensor "
        f"topics {face['forwarding_sensors']['cpu_percent']} % CPU, {face['forwarding_sensors']['rss_mb']} MB"
    )


def _bench_nav2(args: argparse.Namespace) -> int:
    from deploy.bench.nav2 import BenchError, run_bench  # noqa: PLC0415 - starts a stack with the DDS face

    try:
        report = run_bench(args.repeats, idle_s=args.idle_s, busy_s=args.busy_s)
    except (BenchError, RuntimeError) as exc:
        print(f"zendock bench nav2: {exc}", file=sys.stderr)
        return 1
    if args.json:
        print(strict_json.dumps(report))
        return 0
    table = Table(title="from up to waitUntilNav2Active() returning, and the DDS face's cost (medians)")
    for column in ("figure", "median", "runs"):
        table.add_column(column)
    for key, median in report["median"].items():
        table.add_row(key, f"{median:g}", ", ".join(f"{run[key]:g}" for run in report["runs"]))
    Console().print(table)
    return 0


def _bench_ros2(args: argparse.Namespace) -> int:
    from deploy.bench.ros2 import run_ros2_bench, run_stack_rtf  # noqa: PLC0415 - starts a router and the bridge

    try:
        report = run_ros2_bench(messages=args.messages)
        if args.rtf_seconds > 0:
            report["stack_rtf"] = run_stack_rtf(args.world, seconds=args.rtf_seconds)
        if args.dds:
            from deploy.bench.ros2_dds import run as run_dds_bench  # noqa: PLC0415 - needs .venv-ros2

            report["dds"] = run_dds_bench(rtf="1", seconds=args.dds_seconds)
    except RuntimeError as exc:
        print(f"zendock bench ros2: {exc}", file=sys.stderr)
        return 1
    if args.json:
        print(strict_json.dumps(report))
        return 0
    table = Table(title="ROS 2 bridge: latency zendock key -> rmw_zenoh subscriber, against the direct path")
    for column in (
        "topic",
        "bytes",
        "bridge p50",
        "bridge p99",
        "direct p50",
        "added p50",
        "CPU/msg",
        "max msg/s",
    ):
        table.add_column(column, justify="right")
    for topic, row in report["cases"].items():
        table.add_row(
            topic,
            str(row["payload_bytes"]),
            f"{row['bridge_p50_ms']} ms",
            f"{row['bridge_p99_ms']} ms",
            f"{row['direct_p50_ms']} ms",
            f"{row['added_p50_ms']} ms",
            f"{row['bridge_cpu_us_per_message']} us",
            str(row["burst_forwarded_per_s"]),
        )
    Console().print(table)
    if "dds" in report:
        _print_dds(report["dds"])
    for label, rtf in report.get("stack_rtf", {}).items():
        print(f"simulator, battery and pose flat out, {label}: {rtf}x real time")
    return 0


def _bench_messages(args: argparse.Namespace) -> int:
    from pathlib import Path  # noqa: PLC0415

    from deploy.bench.messages import MessageCount  # noqa: PLC0415 - starts a stack
    from deploy.trials import TrialOptions, run_trials  # noqa: PLC0415

    world = Path(args.world)
    count = MessageCount()
    options = TrialOptions(
        world=world.resolve(),
        n=args.n,
        detector=args.detector,
        seed=args.seed,
        rtf=args.rtf,
        compose="all" if args.compose else "",
    )
    console = Console(stderr=True)
    try:
        summary, _, run_dir = run_trials(
            options, log=lambda t: console.print(f"[dim]bench:[/] {t}"), tap=count.tap
        )
        report = count.report()
    except (RuntimeError, ValueError) as exc:
        print(f"zendock bench messages: {exc}", file=sys.stderr)
        return 1
    report.update(
        {
            "docked": f"{summary.successes}/{summary.n}",
            "achieved_rtf": summary.achieved_rtf,
            "detector": args.detector,
            "composed": bool(args.compose),
            "run_dir": str(run_dir),
        }
    )
    if args.json:
        print(strict_json.dumps(report))
        return 0
    table = Table(
        title=f"messages per simulated second, one robot ({report['sim_s']} sim s, {report['docked']} docked)"
    )
    for column in ("key", "published", "delivered", "subscribers"):
        table.add_column(column, justify="left" if column in ("key", "subscribers") else "right")
    for key, row in report["keys"].items():
        table.add_row(
            key,
            f"{row['published_per_sim_s']}",
            f"{row['delivered_per_sim_s']}",
            ", ".join(row["subscribers"]),
        )
    table.add_row(
        "all", f"{report['published_per_sim_s_per_robot']}", f"{report['delivered_per_sim_s_per_robot']}", ""
    )
    Console().print(table)
    return 0


def _bench_record(args: argparse.Namespace) -> int:
    import shutil  # noqa: PLC0415
    import tempfile  # noqa: PLC0415
    from pathlib import Path  # noqa: PLC0415

    from deploy.bench.recording import RecordingTap  # noqa: PLC0415 - starts a stack
    from deploy.trials import TrialOptions, run_trials  # noqa: PLC0415

    world = Path(args.world)
    options = TrialOptions(
        world=world.resolve(),
        n=args.n,
        detector=args.detector,
        seed=args.seed,
        rtf=args.rtf,
        workers=args.workers,
    )
    console = Console(stderr=True)
    scratch = Path(
        tempfile.mkdtemp(prefix="zendock-bench-record-")
    )  # the run directory is made by the campaign
    recorder = RecordingTap(output=scratch / "campaign.mcap", world=world.resolve())
    try:
        summary, _, run_dir = run_trials(
            options, log=lambda t: console.print(f"[dim]bench:[/] {t}"), tap=recorder.tap
        )
        report = recorder.report()
    except (RuntimeError, ValueError) as exc:
        print(f"zendock bench record: {exc}", file=sys.stderr)
        shutil.rmtree(scratch, ignore_errors=True)
        return 1
    kept = run_dir / "campaign.mcap"
    shutil.move(str(recorder.output), kept)
    shutil.rmtree(scratch, ignore_errors=True)
    report.update(
        {
            "docked": f"{summary.successes}/{summary.n}",
            "achieved_rtf": summary.achieved_rtf,
            "detector": args.detector,
            "rtf": args.rtf,
            "workers": args.workers,
            "recording": str(kept),
        }
    )
    if args.json:
        print(strict_json.dumps(report))
        return 0
    table = Table(
        title=f"recording everything through {report['docked']} dockings ({args.detector}, rtf {args.rtf})"
    )
    for column in ("key", "recorded", "lost", "gaps"):
        table.add_column(column, justify="left" if column == "key" else "right")
    for key, row in report["keys"].items():
        table.add_row(key, str(row["recorded"]), str(row["lost"]), str(row["gaps"]))
    Console().print(table)
    print(
        f"{report['recorded']} messages recorded, {report['lost']} lost in {report['gaps']} gap(s); images "
        f"{report['images_recorded']} recorded, {report['images_lost']} lost; recorder peak RSS "
        f"{report['recorder_peak_rss_mb']} MB, CPU {report['recorder_cpu_fraction']} of a core; {kept}"
    )
    return 0


def _bench_startup(args: argparse.Namespace) -> int:
    from deploy.bench.startup import run_startup_bench  # noqa: PLC0415 - starts services

    try:
        report = run_startup_bench(repeats=args.repeats, services=args.services or None)
    except (RuntimeError, ValueError) as exc:
        print(f"zendock bench startup: {exc}", file=sys.stderr)
        return 1
    if args.json:
        print(strict_json.dumps(report))
        return 0
    table = Table(title=f"start-up, exec to liveliness token (median of {report['repeats']})")
    for column in (
        "service",
        "interpreter",
        "imports",
        "session and ready",
        "to token",
        "max",
        "from standby",
    ):
        table.add_column(column, justify="left" if column == "service" else "right")
    for name, row in report["services"].items():
        table.add_row(
            name,
            f"{row['interpreter_ms']} ms",
            f"{row['imports_ms']} ms",
            f"{row['session_and_ready_ms']} ms",
            f"{row['to_token_ms']} ms",
            f"{row['to_token_max_ms']} ms",
            f"{row['from_standby_ms']} ms",
        )
    Console().print(table)
    for name, row in report["services"].items():
        heavy = ", ".join(f"{module} {ms:.0f} ms" for module, ms in row["top_imports_ms"].items())
        print(f"{name}: heaviest imports {heavy}")
    compiled = {name: row["compiled_from_source"] for name, row in report["services"].items()}
    if any(compiled.values()):
        counts = ", ".join(
            f"{name} {n} of {report['services'][name]['own_modules']}" for name, n in compiled.items() if n
        )
        print(
            f"modules compiled from source on import (no fresh bytecode cache): {counts}; these imports "
            "include compiling them: `make` (or `python -m compileall -q shared services deploy`) writes "
            "the cache, which PYTHONDONTWRITEBYTECODE stops Python from writing itself"
        )
    else:
        print("every zendock module came from its bytecode cache")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("bench", help="benchmarks (latency, throughput, planning, docking)")
    verbs = parser.add_subparsers(dest="bench", metavar="BENCH")
    verbs.required = True
    bus = verbs.add_parser("bus", help="typed pub/sub round trip vs raw zenoh-python, two processes")
    bus.add_argument("--rounds", type=int, default=4000, help="round trips on each path, interleaved")
    bus.add_argument("--json", action="store_true")
    bus.set_defaults(func=_bench_bus)
    sim = verbs.add_parser("sim", help="simulator steps per second with all sensors, as a real-time factor")
    sim.add_argument("--world", type=world_file_argument, default="deploy/worlds/seed_room.yaml")
    sim.add_argument("--seconds", type=float, default=60.0, help="simulated seconds to run")
    sim.add_argument("--json", action="store_true")
    sim.set_defaults(func=_bench_sim)

    perception = verbs.add_parser(
        "perception", help="dock detection from rendered camera images: rate, error, latency"
    )
    perception.add_argument("--frames", type=int, default=12, help="frames per viewpoint")
    perception.add_argument("--json", action="store_true")
    perception.set_defaults(func=_bench_perception)
    messages = verbs.add_parser(
        "messages", help="messages per simulated second per key and subscriber, docking"
    )
    messages.add_argument("--world", type=world_file_argument, default="deploy/worlds/seed_room.yaml")
    messages.add_argument("--n", type=count, default=5, help="dockings from random starts")
    messages.add_argument(
        "--rtf", type=real_time_factor, default="8", help="simulator real-time factor, or max"
    )
    add_detector_option(messages, "aruco")
    messages.add_argument("--seed", type=int, default=0)
    messages.add_argument("--compose", action="store_true", help="the robot's services in one process")
    messages.add_argument("--json", action="store_true")
    messages.set_defaults(func=_bench_messages)
    record = verbs.add_parser(
        "record", help="record everything, camera included, through a docking campaign: gaps"
    )
    record.add_argument("--world", type=world_file_argument, default="deploy/worlds/seed_room.yaml")
    record.add_argument("--n", type=count, default=3, help="dockings from random starts")
    record.add_argument(
        "--rtf",
        type=real_time_factor,
        default="1",
        help="simulator real-time factor, or max (1: as a real run)",
    )
    record.add_argument("--workers", type=count, default=1, help="robots docking side by side")
    add_detector_option(record, "aruco")
    record.add_argument("--seed", type=int, default=0)
    record.add_argument("--json", action="store_true")
    record.set_defaults(func=_bench_record)
    startup = verbs.add_parser(
        "startup", help="where a service's start-up goes: interpreter, imports, session"
    )
    startup.add_argument("services", nargs="*", metavar="SERVICE", help="default: the stack's robot services")
    startup.add_argument("--repeats", type=int, default=5, help="starts per service (medians)")
    startup.add_argument("--json", action="store_true")
    startup.set_defaults(func=_bench_startup)
    nav2 = verbs.add_parser(
        "nav2", help="from up to a Nav2 script's waitUntilNav2Active(), and the DDS face's CPU and RSS"
    )
    nav2.add_argument("--repeats", type=count, default=3, help="stacks started (medians)")
    nav2.add_argument("--idle-s", type=float, default=10.0, help="seconds the idle face's CPU is measured")
    nav2.add_argument("--busy-s", type=float, default=8.0, help="seconds the busy face's CPU is measured")
    nav2.add_argument("--json", action="store_true")
    nav2.set_defaults(func=_bench_nav2)
    ros2 = verbs.add_parser(
        "ros2", help="the ROS 2 bridge: added latency, CPU per message, throughput by type"
    )
    ros2.add_argument("--messages", type=int, default=1000, help="paced messages per type")
    ros2.add_argument(
        "--rtf-seconds",
        type=float,
        default=10.0,
        help="wall seconds per condition of the stack's real-time factor (0: skip)",
    )
    ros2.add_argument(
        "--world",
        type=world_argument,
        default="deploy/worlds/seed_room.yaml",
        help="world of the real-time-factor runs",
    )
    ros2.add_argument(
        "--dds",
        action="store_true",
        help="also the DDS face on real rclpy (needs .venv-ros2: make ros2), beside rclpy-to-rclpy",
    )
    ros2.add_argument("--dds-seconds", type=float, default=10.0, help="length of each DDS measuring phase")
    ros2.add_argument("--json", action="store_true")
    ros2.set_defaults(func=_bench_ros2)
    planner = verbs.add_parser(
        "planner", help="planning time on a 20 m room; time to goal with the real stack vs the shortest path"
    )
    planner.add_argument("--repeats", type=int, default=5, help="planning repeats per route (medians)")
    planner.add_argument("--resolution", type=float, default=0.05, help="costmap resolution, metres")
    planner.add_argument("--planning-only", action="store_true", help="skip the runs in the simulator")
    planner.add_argument("--rtf", type=float, default=5.0, help="real-time factor of the simulator runs")
    planner.add_argument("--timeout", type=float, default=120.0, help="wall seconds allowed per goal")
    planner.add_argument("--json", action="store_true")
    planner.set_defaults(func=_bench_planner)
    docking = verbs.add_parser(
        "docking", help="final approach: seed vs Nav2-default graceful vs tuned, kinematic model"
    )
    docking.add_argument("--latency", type=float, default=0.05, help="pose latency, s")
    docking.add_argument("--seed", type=int, default=0, help="noise seed")
    docking.add_argument("--json", action="store_true")
    docking.set_defaults(func=_bench_docking)
    ir = verbs.add_parser("ir", help="infrared docking from beacon starts in world files, kinematic model")
    ir.add_argument(
        "--world",
        type=world_argument,
        action="append",
        metavar="FILE|DIR",
        help="world file or directory of them (repeatable; default deploy/worlds/unseen)",
    )
    ir.add_argument("--n", type=int, default=20, help="beacon starts per world")
    ir.add_argument("--seed", type=int, default=1)
    ir.add_argument("--json", action="store_true")
    ir.set_defaults(func=_bench_ir)
