"""``zendock bench ...``: measurements, not tests. Each prints a table, or JSON with ``--json``."""

from __future__ import annotations

import argparse
import json
import sys

from rich.console import Console
from rich.table import Table


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
    from deploy.bench.bus import run_bus_bench

    result = run_bus_bench(rounds=args.rounds, blocks=args.blocks)
    _print(result.as_dict(), args.json, "bus round trip: zendock typed vs raw zenoh-python")
    return 0


def _bench_sim(args: argparse.Namespace) -> int:
    try:
        from services.simulator.bench import bench_simulation  # noqa: PLC0415 - the simulator's own core
    except ImportError:
        print("zendock bench sim: the simulator is not installed", file=sys.stderr)
        return 1
    _print(bench_simulation(args.world, args.seconds), args.json, "simulator throughput (all sensors on)")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("bench", help="benchmarks (latency, throughput, planning, docking)")
    verbs = parser.add_subparsers(dest="bench", metavar="BENCH")
    verbs.required = True
    bus = verbs.add_parser("bus", help="typed pub/sub round trip vs raw zenoh-python, two processes")
    bus.add_argument("--rounds", type=int, default=4000)
    bus.add_argument("--blocks", type=int, default=4, help="alternate typed/raw blocks to share the noise")
    bus.add_argument("--json", action="store_true")
    bus.set_defaults(func=_bench_bus)
    sim = verbs.add_parser("sim", help="simulator steps per second with all sensors, as a real-time factor")
    sim.add_argument("--world", default="deploy/worlds/seed_room.yaml")
    sim.add_argument("--seconds", type=float, default=60.0, help="simulated seconds to run")
    sim.add_argument("--json", action="store_true")
    sim.set_defaults(func=_bench_sim)
