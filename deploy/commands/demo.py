"""``zendock demo``: bring the stack up, let the battery run low, dock, report (what ``make run`` runs)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from rich.console import Console
from rich.table import Table

from deploy import strict_json
from deploy.arg_types import add_service_option, check_replacements, positive_number, real_time_factor
from deploy.options import add_controller_option, add_detector_option, add_runs_dir_option
from deploy.progress import is_terminal, progress_period_s
from deploy.world_names import world_file_argument
from shared.config_errors import ConfigError
from shared.world import load_world


def _measure(value: float | None, scale: float, template: str) -> str:
    """``template`` filled with ``scale * value``, or ``n/a`` for a measure that was not taken (NaN or null)."""
    if value is None or not math.isfinite(value):
        return "n/a"
    return template.format(scale * value)


def _print_report(report: dict, console: Console) -> None:
    table = Table(title=f"zendock demo: {report['world']} with the {report['controller']} controller")
    table.add_column("measure")
    table.add_column("value", justify="right")
    rows = [
        ("docked and charging", "yes" if report["docked"] and report["charging"] else "NO"),
        ("dock time (trigger to CHARGING)", _measure(report["dock_time_s"], 1.0, "{:.1f} s sim")),
        ("lower bound", _measure(report["lower_bound_s"], 1.0, "{:.1f} s sim")),
        ("narrowest gap on the way (glass solid)", _measure(report.get("way_width_m"), 1.0, "{:.2f} m")),
        ("lateral error at contact", _measure(report["final_lateral_error_m"], 1000.0, "{:.1f} mm")),
        ("yaw error at contact", _measure(report["final_yaw_error_rad"], 180.0 / math.pi, "{:.2f} deg")),
        ("collisions", str(report["collisions"])),
        ("path driven", _measure(report["path_length_m"], 1.0, "{:.2f} m")),
        ("speed meeting the plate", _measure(report.get("arrival_speed_mps"), 1.0, "{:.3f} m/s")),
        ("false glass cells (>10 cm from a pane)", _measure(report.get("false_glass_cells"), 1.0, "{:.0f}")),
        ("glass length found", _measure(report.get("glass_coverage"), 100.0, "{:.0f} %")),
        ("wall time", _measure(report["wall_s"], 1.0, "{:.1f} s")),
    ]
    if report.get("lower_bound_s_reason"):
        rows.insert(3, ("why no lower bound", report["lower_bound_s_reason"]))
    rows += [
        (f"peak RSS {name}", f"{mb:.0f} MB") for name, mb in sorted(report.get("peak_rss_mb", {}).items())
    ]
    rows += [
        (f"{name} replaced by", command)
        for name, command in sorted(report.get("replaced_services", {}).items())
    ]
    for name, value in rows:
        table.add_row(name, value)
    console.print(table)
    console.print(f"report and trajectory picture in {report['run_dir']}")


def _run(args: argparse.Namespace) -> int:
    from deploy.demo import DemoOptions, run_demo  # noqa: PLC0415 - heavy imports only when used

    world = Path(args.world)
    room = load_world(world)  # a bad world file or start pose is one line, before any process starts
    problem = room.placement_problem(args.start[0], args.start[1]) if args.start else None
    if problem:
        raise ConfigError(f"--start {problem} of world {world}")
    console = Console(stderr=args.json)
    options = DemoOptions(
        world=world.resolve(),
        controller=args.controller,
        detector=args.detector,
        rtf=args.rtf,
        seed=args.seed,
        start=tuple(args.start) if args.start else None,
        timeout_sim_s=args.timeout,
        compose=args.compose,
        replacements=check_replacements(args.replacements),
        **({"runs_dir": args.runs_dir} if args.runs_dir else {}),
    )
    # progress every 2 s on a terminal; with --json or into a pipe, a line every 10 s on stderr only
    interactive = not args.json and is_terminal(sys.stdout)
    progress_console = console if interactive else Console(stderr=True)
    report = run_demo(
        options,
        log=lambda text: console.print(f"[dim]demo:[/] {text}"),
        status=lambda text: progress_console.print(f"[dim]demo:[/] {text}", highlight=False),
        status_period_s=progress_period_s(interactive),
    ).as_dict()
    _print_report(report, console)
    if args.json:
        print(strict_json.dumps(report))
    return 0 if report["docked"] and report["charging"] else 1


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "demo", help="dock once on the full stack and report (what `make run` runs)"
    )
    parser.add_argument(
        "--world", type=world_file_argument, default="deploy/worlds/seed_room.yaml", help="world file"
    )
    parser.add_argument(
        "--compose",
        action="store_true",
        help="the robot's services in one process (zendock container) instead of one process each",
    )
    add_controller_option(parser)
    add_detector_option(parser, "aruco")
    parser.add_argument(
        "--rtf", type=real_time_factor, default="1.0", help="real-time factor of the simulator, or max"
    )
    parser.add_argument("--seed", type=int, default=0, help="simulator noise seed")
    parser.add_argument(
        "--start", type=float, nargs=3, metavar=("X", "Y", "YAW"), help="start pose (map frame)"
    )
    parser.add_argument(
        "--timeout",
        type=positive_number,
        default=300.0,
        metavar="SIM_SECONDS",
        help="give up this many sim seconds after the trigger",
    )
    add_service_option(parser)
    add_runs_dir_option(parser)
    parser.add_argument("--json", action="store_true", help="print the JSON report as the last line")
    parser.set_defaults(func=_run)
