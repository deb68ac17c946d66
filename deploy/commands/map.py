"""``zendock map save``: the occupancy map a lidar would build of a world file, in map_server format.

Writes ``<DIR>/<world name>.yaml`` and ``.pgm`` (or the ``.yaml`` path given) and prints both paths.
Glass is left out of the map on purpose (the lidar sees through it); the planner's range layer adds it
at run time. The rasterising is the planner's own code, run as a process (``services.planner.map_save``).
"""

from __future__ import annotations

import argparse

from deploy.service_tools import run_tool


def _save(args: argparse.Namespace) -> int:
    argv = [
        "--world",
        args.world,
        "-o",
        args.output,
        "--resolution",
        str(args.resolution),
        "--padding",
        str(args.padding),
    ]
    return run_tool("services.planner.map_save", argv).echo()


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("map", help="occupancy maps (map_server YAML + PGM)")
    verbs = parser.add_subparsers(dest="map_command", metavar="VERB")
    verbs.required = True
    save = verbs.add_parser(
        "save", help="rasterise a world file into <DIR>/<world>.yaml and .pgm (or FILE.yaml)"
    )
    save.add_argument("--world", required=True, help="world file (deploy/worlds/*.yaml)")
    save.add_argument(
        "-o",
        "--output",
        default=".",
        metavar="DIR|FILE.yaml",
        help="output directory, or the map's .yaml path (default: .)",
    )
    save.add_argument("--resolution", type=float, default=0.05, help="metres per cell (default: 0.05)")
    save.add_argument(
        "--padding",
        type=float,
        default=0.5,
        help="unknown margin around the world's bounds, metres (default: 0.5)",
    )
    save.set_defaults(func=_save)
