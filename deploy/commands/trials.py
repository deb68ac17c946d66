"""``zendock trials``: Monte Carlo dockings from random starts, with a progress bar and a summary."""

from __future__ import annotations

import argparse
import math
import sys
import threading
import time
from pathlib import Path

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table

from deploy import strict_json
from deploy.arg_types import add_service_option, check_replacements, count, real_time_factor, seed
from deploy.options import add_controller_option, add_detector_option, add_runs_dir_option, add_standby_option
from deploy.progress import TRIALS_PER_LINE, is_terminal, trials_line
from deploy.world_names import campaign_world, generated_kind
from shared.config_errors import ConfigError
from shared.controllers import CONTROLLERS
from shared.world import world_files

SHIPPED_WORLDS = Path(__file__).resolve().parents[1] / "worlds"
DEFAULT_WORLD = "deploy/worlds/seed_room.yaml"


def _summary_table(summary: dict) -> Table:
    table = Table(title=f"{summary['n']} trials: {summary['world']}, {summary['controller']} controller")
    table.add_column("measure")
    table.add_column("value", justify="right")
    fmt = {
        "success_rate": lambda v: f"{100 * v:.1f} %",
        "median_lateral_error_m": lambda v: f"{1000 * v:.1f} mm",
        "p95_lateral_error_m": lambda v: f"{1000 * v:.1f} mm",
        "median_yaw_error_rad": lambda v: f"{math.degrees(v):.2f} deg",
        "median_arrival_speed_mps": lambda v: f"{v:.3f} m/s",
        "max_arrival_speed_mps": lambda v: f"{v:.3f} m/s",
        "median_glass_coverage": lambda v: f"{100 * v:.0f} %",
        "heard_panes_found": lambda v: f"{100 * v:.0f} %",
        "p05_glass_clearance_m": lambda v: f"{100 * v:.1f} cm",
    }
    from deploy.trials.records import HEADLINE_KEYS  # noqa: PLC0415 - the package loads the campaign

    for key in HEADLINE_KEYS:
        if key == "n":  # the table's title says it
            continue
        value = summary[key]
        text = fmt[key](value) if key in fmt else (f"{value:.1f}" if isinstance(value, float) else str(value))
        table.add_row(key, text)
    for name, seconds in summary.get("median_phase_s", {}).items():
        table.add_row(f"median s in {name}", f"{seconds:.1f}")
    for part, seconds in summary.get("median_over_bound_s", {}).items():
        table.add_row(f"median s over the bound: {part}", f"{seconds:.2f}")
    slowed = summary.get("median_glass_slowed_s")
    if isinstance(slowed, float) and math.isfinite(slowed):
        table.add_row("median s slowed for glass (navigating)", f"{slowed:.1f}")
    for name, mb in sorted(summary.get("peak_rss_mb", {}).items()):
        table.add_row(f"peak RSS {name}", f"{mb:.0f} MB")
    for name, seconds in sorted(summary.get("cpu_s_per_sim_s", {}).items()):
        table.add_row(f"CPU {name}", f"{1000 * seconds:.0f} ms per sim s")
    return table


def _worlds(args: argparse.Namespace) -> list[tuple[Path, int]]:
    """Each world of the campaign with its number of trials: ``--n`` each, or for ``generated:KIND`` one
    trial in each of ``--n`` fresh rooms (seeds from ``--seed``), written under the runs directory."""
    names = args.world or [DEFAULT_WORLD]
    if names == ["all"]:
        return [(world.resolve(), args.n) for world in sorted(SHIPPED_WORLDS.glob("*.yaml"))]
    out: list[tuple[Path, int]] = []
    for name in names:
        kind = generated_kind(name)  # checked by campaign_world
        if kind is not None:
            out += [(room.resolve(), 1) for room in _generated_rooms(args, kind)]
            continue
        worlds = world_files([name])  # a directory stands for every world file in it (deploy/worlds/unseen)
        if not worlds:
            raise ConfigError(f"--world {name}: no world file (*.yaml) there")
        for world in worlds:
            if not world.is_file():
                raise ConfigError(f"--world {world}: no such file")
        out += [(world.resolve(), args.n) for world in worlds]
    return out


def _several_worlds(args: argparse.Namespace) -> bool:
    """Whether the campaign may run ``--n`` trials in each of several worlds (then only its whole count, known
    once its worlds are, bounds the shards; a ``generated:KIND`` campaign is ``--n`` trials in all)."""
    names = args.world or [DEFAULT_WORLD]
    return len(names) > 1 or any(name == "all" or Path(name).is_dir() for name in names)


def _generated_rooms(args: argparse.Namespace, kind: str) -> list[Path]:
    from deploy.generated_worlds import generate_rooms  # noqa: PLC0415 - the planner's tool only when used
    from deploy.paths import RUNS_DIR  # noqa: PLC0415

    directory = (args.runs_dir or RUNS_DIR) / "generated" / f"{kind}-seed{args.seed}-n{args.n}"
    try:
        return generate_rooms(kind, args.seed, args.n, directory)
    except RuntimeError as exc:
        raise ConfigError(f"--world generated:{kind}: {exc}") from None


def _run(args: argparse.Namespace) -> int:
    from deploy.trials import TrialOptions, run_trials  # noqa: PLC0415 - heavy imports only when used

    if args.shard.count > args.n and not _several_worlds(args):
        raise ConfigError(f"--shard {args.shard}: {args.n} trials cannot make {args.shard.count} shards")
    worlds = _worlds(args)
    total = sum(n for _, n in worlds)
    if args.shard.count > total:
        raise ConfigError(f"--shard {args.shard}: {total} trials cannot make {args.shard.count} shards")
    console = Console(stderr=args.json)
    per_world = []
    shards = args.shard.in_worlds([n for _, n in worlds])
    for number, ((world, n), shard) in enumerate(zip(worlds, shards, strict=True)):
        if shard is None:  # every trial of this world is another shard's
            continue
        # each world its own seed, so a campaign does not repeat one pattern of starts everywhere
        starts = args.starts or CONTROLLERS[args.controller].starts
        options = TrialOptions(
            world=world,
            n=n,
            controller=args.controller,
            detector=args.detector,
            starts=starts,
            seed=args.seed + 1000 * number,
            rtf=args.rtf,
            workers=args.workers,
            timeout_sim_s=args.timeout,
            chaos_period_s=args.chaos,
            standby=args.standby,
            compose=args.compose,
            shard=shard,
            replacements=check_replacements(args.replacements),
            **({"runs_dir": args.runs_dir} if args.runs_dir else {}),
        )
        try:
            summary, results, run_dir = _run_world(console, options, run_trials)
        except (
            RuntimeError,
            ValueError,
        ) as exc:  # a world the campaign cannot run (no reachable start, no dock)
            raise ConfigError(f"trials in {world}: {exc}") from None
        per_world.append((summary, results))
        _print_summary(console, summary)
        for line in collision_lines(results, options):
            console.print(line, highlight=False, soft_wrap=True)
        console.print(f"report and histograms in {run_dir}")
    return _report_campaign(console, per_world, args.controller, args.json)


def _report_campaign(console: Console, per_world: list, controller: str, as_json: bool) -> int:
    """The campaign's summary across worlds (printed when there are several), the JSON line; the exit code."""
    from deploy.trials import combine  # noqa: PLC0415
    from deploy.trials.summary import summary_reasons  # noqa: PLC0415

    summary = per_world[0][0] if len(per_world) == 1 else combine(per_world, controller)
    if len(per_world) > 1:
        _print_summary(console, summary)
    if as_json:
        line = {**summary.headline(), **({"chaos": summary.chaos} if summary.chaos else {})}
        if len(per_world) > 1:
            line["worlds"] = {s.world: s.headline() for s, _ in per_world}
        print(strict_json.dumps(line, reasons=summary_reasons(summary)))
    return 0 if summary.successes == summary.n else 1


def _merge(args: argparse.Namespace) -> int:
    from deploy.paths import RUNS_DIR  # noqa: PLC0415
    from deploy.trials.merge import MergeError, find_reports, merge_reports, read_shard, write_merged  # noqa: PLC0415

    console = Console(stderr=args.json)
    try:
        reports = [read_shard(path) for path in find_reports(args.paths)]
        merged = merge_reports(reports)
    except MergeError as exc:
        raise ConfigError(str(exc)) from None
    out = write_merged(merged, args.runs_dir or RUNS_DIR)
    per_world = []
    for result in merged.values():
        _print_summary(console, result.summary)
        per_world.append((result.summary, result.trials))
    console.print(f"merged {len(reports)} shard report(s); report and histograms in {out}")
    return _report_campaign(console, per_world, per_world[0][0].controller, args.json)


def _shard(text: str):
    from deploy.trials.records import Shard  # noqa: PLC0415

    try:
        return Shard.parse(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _run_world(console: Console, options, run_trials):
    """One world's trials, with progress on stderr: a rich bar on a terminal, else a line every 10 trials.

    stdout keeps only the header, the summary and (``--json``) the JSON line, whatever the progress does.
    """
    total = len(options.shard.select(range(options.n)))
    log = lambda t: console.print(f"[dim]trials:[/] {t}")  # noqa: E731
    lock = threading.Lock()
    tally = {"done": 0, "docked": 0}
    if not is_terminal(sys.stderr):
        began = time.monotonic()
        err = Console(stderr=True, highlight=False)

        def count(result) -> None:
            with lock:
                tally["done"] += 1
                tally["docked"] += bool(result.docked)
                done = tally["done"]
                if done == 1 or done % TRIALS_PER_LINE == 0 or done == total:  # the first: the pace, early
                    err.print(
                        trials_line(
                            world=options.world.stem,
                            done=done,
                            total=total,
                            successes=tally["docked"],
                            elapsed_s=time.monotonic() - began,
                        )
                    )

        return run_trials(options, log=log, progress=count)
    with Progress(
        TextColumn(f"trials {options.world.stem}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[docked]} docked"),
        TextColumn("{task.fields[last]}"),
        TimeElapsedColumn(),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        redirect_stdout=is_terminal(sys.stdout),
    ) as bar:
        task = bar.add_task("trials", total=total, last="", docked=0)

        def advance(result) -> None:
            status = (
                "docked"
                if result.docked
                else "FAILED (met the plate too fast)"
                if result.too_fast
                else "FAILED"
            )
            with lock:
                tally["docked"] += bool(result.docked)
                bar.update(
                    task,
                    advance=1,
                    docked=tally["docked"],
                    last=f"#{result.index} {status} {result.dock_time_s:.1f} s",
                )

        return run_trials(options, log=log, progress=advance)


def collision_lines(results: list, options) -> list[str]:
    """One line per trial that touched something or did not dock: what, where, and a command that starts it
    again from the same pose (a world's starts are drawn from its seed in order, so its first ``index + 1``
    end with this one's; a generated room's seed is the campaign's plus 1000 for each room before it)."""
    lines = []
    for r in results:
        x, y, yaw = r.start
        trial = f"{options.world.stem} trial {r.index} from ({x:.2f}, {y:.2f}, {yaw:.2f})"
        if r.collided:
            touched = ", ".join(f"{c['kind']} at ({c['x']:.2f}, {c['y']:.2f})" for c in r.collided)
            what = f"collision: {trial} touched {touched}"
        elif r.too_fast:
            what = f"not docked: {trial} met the plate faster than the contact speed limit"
        elif not r.docked:
            what = f"not docked: {trial} did not charge within the trial's limit"
        else:
            continue
        lines.append(
            f"{what}; again: zendock trials --world {options.world} --n {r.index + 1} --seed {options.seed} "
            f"--controller {options.controller} --detector {options.detector} --rtf {options.rtf}"
        )
    return lines


def _print_summary(console: Console, summary) -> None:
    data = {
        **summary.headline(),
        "controller": summary.controller,
        "world": summary.world,
        "peak_rss_mb": summary.peak_rss_mb,
        "cpu_s_per_sim_s": summary.cpu_s_per_sim_s,
        "median_glass_slowed_s": summary.median_glass_slowed_s,
    }
    console.print(_summary_table(data))
    if summary.chaos:
        chaos = summary.chaos
        console.print(
            f"chaos: {chaos['kills']} kill -9, {chaos['recovered']} back healthy, recovery median "
            f"{chaos['median_recovery_s']} s, p95 {chaos['p95_recovery_s']} s, max {chaos['max_recovery_s']} s"
        )


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("trials", help="Monte Carlo dockings from random starts on the full stack")
    parser.add_argument(
        "--world",
        type=campaign_world,
        action="append",
        metavar="FILE|DIR|generated:KIND",
        help=f"world file or directory of them (repeat for a campaign across worlds; 'all': every shipped world; "
        f"generated:room or generated:glass: --n fresh rooms drawn from --seed, one docking each); "
        f"default {DEFAULT_WORLD}",
    )
    parser.add_argument(
        "--n", type=count, default=10, help="number of dockings (per world; with generated:KIND, of rooms)"
    )
    add_controller_option(parser)
    parser.add_argument(
        "--starts",
        choices=["room", "beacon"],
        default=None,
        help="room: anywhere reachable, away from the dock; beacon: within 2 m in front of it "
        "(default: beacon for --controller ir, room otherwise)",
    )
    add_detector_option(parser, "aruco")
    parser.add_argument(
        "--seed", type=seed, default=0, help="seed of the start poses and the simulator's noise"
    )
    parser.add_argument(
        "--rtf", type=real_time_factor, default="8", help="simulator real-time factor, or max"
    )
    parser.add_argument(
        "--workers", type=count, default=1, help="robots docking side by side in one simulator"
    )
    parser.add_argument("--timeout", type=float, default=240.0, metavar="SIM_SECONDS", help="limit per trial")
    parser.add_argument(
        "--chaos",
        type=float,
        default=0.0,
        metavar="PERIOD_S",
        help="kill -9 a random robot service (with --compose: a robot's group process) every "
        "PERIOD_S wall seconds on average (0: off)",
    )
    add_standby_option(parser)
    parser.add_argument(
        "--compose",
        nargs="?",
        const="all",
        default="",
        choices=["all", "light"],
        help="each robot's services in one process (zendock container): all of them (the default "
        "with the flag), or only the light ones (battery, pose)",
    )
    parser.add_argument(
        "--shard",
        type=_shard,
        default="1/1",
        metavar="K/N",
        help="run only the K-th of N disjoint slices of the campaign (the same starts as the "
        "whole run, its trials dealt out in turn across its worlds: with generated:KIND, every N-th "
        "room; combine them with `zendock trials merge`)",
    )
    add_runs_dir_option(parser, "run directories go")
    add_service_option(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as JSON on the last line")
    parser.set_defaults(func=_run)
    verbs = parser.add_subparsers(dest="trials_verb", metavar="merge")
    merge = verbs.add_parser(
        "merge",
        help="combine shard runs into the campaign's one summary",
        description="Combine the reports of `zendock trials --shard K/N` runs into the one "
        "summary, histograms and trials.json the unsharded campaign gives.",
    )
    merge.add_argument(
        "paths",
        nargs="+",
        type=Path,
        metavar="PATH",
        help="a shard's trials.json, its run directory, or a directory holding shard runs",
    )
    add_runs_dir_option(merge, "the merged run directory goes")
    merge.add_argument(
        "--json", action="store_true", help="print the merged summary as JSON on the last line"
    )
    merge.set_defaults(func=_merge, command_path="trials merge")
