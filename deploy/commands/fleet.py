"""``zendock fleet``: several robots patrol one room and share its docks; live progress and a report."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from rich.console import Console
from rich.live import Live
from rich.table import Table
from rich.text import Text

from deploy import strict_json
from deploy.arg_types import add_service_option, check_replacements, count, positive_number, real_time_factor
from deploy.options import add_detector_option, add_runs_dir_option
from deploy.progress import is_terminal
from deploy.world_names import world_file_argument
from shared.config_errors import ConfigError

DEFAULT_WORLD = "deploy/worlds/fleet/warehouse.yaml"
#: How often the terminal's live table is refreshed from the bus (wall seconds).
LIVE_PERIOD_S = 1.0


def _fraction(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0.3 < value <= 1.0:
        raise argparse.ArgumentTypeError(
            f"must be a fraction in (0.3, 1], above the docking threshold 0.25, got {text}"
        )
    return value


def _table(report) -> Table:
    table = Table(
        title=f"fleet in {report.world}: {report.sim_s:.0f} s simulated in {report.wall_s:.0f} s "
        f"(rtf {report.achieved_rtf})"
    )
    for column in ("robot", "distance", "dockings", "min battery", "waiting", "collisions"):
        table.add_column(column, justify="left" if column == "robot" else "right")
    for r in report.robots:
        table.add_row(
            r.name,
            f"{r.distance_m:.0f} m",
            str(r.dockings),
            f"{100 * r.min_battery:.0f} %",
            f"{r.wait_s:.0f} s",
            str(r.collisions),
        )
    return table


def live_table(sim_s: float, duration_s: float, robots) -> Table:
    """The robots now, for the terminal's live view: charge, docking state, dockings, distance driven."""
    table = Table(title=f"fleet: {sim_s:.0f} s of {duration_s:.0f} s simulated", title_justify="left")
    for column in ("robot", "charge", "state", "dockings", "distance", "waiting", "collisions"):
        table.add_column(column, justify="left" if column in ("robot", "state") else "right")
    for r in robots:
        charge = f"{100 * r.battery:.0f} %" if math.isfinite(r.battery) else "?"
        if r.charging:
            charge += " +"
        table.add_row(
            r.name,
            charge,
            r.state or "?",
            str(r.dockings),
            f"{r.distance_m:.0f} m",
            f"{r.wait_s:.0f} s",
            str(r.collisions),
        )
    return table


def _run(args: argparse.Namespace) -> int:
    from deploy.fleet.run import LONG_GIVE_WAY_S, run_fleet  # noqa: PLC0415 - heavy imports only when used
    from deploy.fleet.stack import FleetOptions  # noqa: PLC0415

    world = Path(args.world)
    options = FleetOptions(
        world=world.resolve(),
        robots=args.robots,
        duration_s=args.duration,
        rtf=args.rtf,
        seed=args.seed,
        detector=args.detector,
        drain_scale=args.drain_scale,
        charge_scale=args.charge_scale,
        resume_at=args.resume_at,
        replacements=check_replacements(args.replacements),
        compose=args.compose,
        **({"runs_dir": args.runs_dir} if args.runs_dir else {}),
    )
    console = Console(stderr=args.json)
    live_wanted = not args.json and is_terminal(sys.stdout)
    # a live table on a terminal; otherwise a line every 10 s on stderr, so stdout stays the report

    def progress_line(sim_s: float, robots) -> None:
        # plain text: a styled console caches each new line it measures, and a long run prints thousands
        parts = [f"{r.name} {r.state or '?'} {100 * r.battery:.0f}% {r.dockings}d" for r in robots]
        print(f"{sim_s:7.0f} s " + " | ".join(parts), file=sys.stderr, flush=True)

    def log(text: str) -> None:
        console.print(f"[dim]fleet:[/] {text}")

    try:
        if live_wanted:
            with Live(
                Text("fleet: starting the stack"), console=console, refresh_per_second=2, transient=True
            ) as live:
                report, run_dir = run_fleet(
                    options,
                    log=log,
                    progress_period_s=LIVE_PERIOD_S,
                    progress=lambda sim_s, robots: live.update(live_table(sim_s, options.duration_s, robots)),
                )
        else:
            report, run_dir = run_fleet(options, log=log, progress=progress_line)
    except ConfigError:
        raise  # already names the file and what is wrong
    except (RuntimeError, ValueError) as exc:
        raise ConfigError(f"fleet in {world}: {exc}") from None
    console.print(_table(report))
    collisions = report.collisions
    console.print(
        f"collisions: {collisions['robot_robot']} robot-robot, {collisions['robot_world']} robot-world; "
        f"reservation conflicts: {report.reservation_conflicts}; gave way {report.give_ways} time(s)"
        + (
            f", the longest {report.max_give_way_s} s, the median {report.median_give_way_s} s, "
            f"{report.long_give_ways} longer than {LONG_GIVE_WAY_S:g} s"
            if report.give_ways
            else ""
        )
    )
    for conflict in report.conflicts:
        console.print(f"  conflict at {conflict}")
    for error in report.errors:
        console.print(f"[red]error:[/] {error}")
    console.print(f"report, picture and logs in {run_dir}")
    if args.json:
        print(strict_json.dumps(report.to_json()))
    clean = collisions["total"] == 0 and report.reservation_conflicts == 0 and not report.errors
    return 0 if clean else 1


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "fleet",
        help="several robots patrol one room and share its docks, measured",
        description="Run a fleet: each robot patrols, asks the fleet service for a dock "
        "when low, charges, and patrols again. Reports per robot distance, "
        "dockings, lowest charge, time waiting for a dock and collisions, "
        "and the room's reservation conflicts.",
    )
    parser.add_argument(
        "--world",
        type=world_file_argument,
        default=DEFAULT_WORLD,
        metavar="FILE",
        help=f"a world with docks (and robots; default {DEFAULT_WORLD})",
    )
    parser.add_argument(
        "--robots",
        type=count,
        default=None,
        metavar="N",
        help="how many robots (default: those the world lists; more are placed at seeded starts)",
    )
    parser.add_argument(
        "--duration",
        type=positive_number,
        default=600.0,
        metavar="SIM_S",
        help="simulated seconds to run (default 600)",
    )
    parser.add_argument(
        "--rtf", type=real_time_factor, default="4", help="simulator real-time factor, or max"
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of generated starts, patrols and sensor noise"
    )
    add_detector_option(parser, "synthetic")
    parser.add_argument(
        "--drain-scale",
        type=positive_number,
        default=8.0,
        metavar="X",
        help="batteries drain X times faster than the cell model, so an hour holds several charge "
        "cycles (default 8)",
    )
    parser.add_argument(
        "--charge-scale",
        type=positive_number,
        default=16.0,
        metavar="X",
        help="docks charge X times faster than the cell model's 0.5 C (default 16)",
    )
    parser.add_argument(
        "--resume-at",
        type=_fraction,
        default=0.8,
        metavar="FRACTION",
        help="charge at which a docked robot undocks and patrols again (default 0.8)",
    )
    add_runs_dir_option(parser)
    add_service_option(parser)
    parser.add_argument(
        "--compose",
        nargs="?",
        const="all",
        default="",
        choices=["all", "light"],
        help="each robot's services in one process (zendock container): all of them (the default "
        "with the flag), or only the light ones (battery, pose)",
    )
    parser.add_argument("--json", action="store_true", help="print the report as JSON on the last line")
    parser.set_defaults(func=_run)
