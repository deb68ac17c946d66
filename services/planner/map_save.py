"""The occupancy map a lidar would build of a world file, in map_server format (``zendock map save``).

Run as ``python -m services.planner.map_save --world FILE -o DIR|FILE.yaml``; the ``zendock`` CLI and
the stack's map step start it as a process.

Writes ``<DIR>/<world name>.yaml`` and ``<DIR>/<world name>.pgm`` and prints both paths. Glass is left
out of the map on purpose (the lidar sees through it); the planner's range layer adds it at run time.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

from services.planner.occupancy_map import save_map
from services.planner.rasterize import map_from_world
from shared.config_errors import ConfigError
from shared.world import load_world


def _safe_stem(name: str) -> str:
    """A world name as a file name: letters, digits, '-', '_' and '.'; anything else becomes '_'."""
    stem = re.sub(r"[^A-Za-z0-9_.-]", "_", name).strip(".")
    return stem or "map"


def save_world_map(
    world_file: str | Path, output: str | Path, resolution_m: float, padding_m: float
) -> tuple[Path, Path]:
    """Rasterise ``world_file`` and write the map; returns ``(yaml_path, pgm_path)``.

    ``output`` is a directory (the map is named after the world) or a ``.yaml`` file path (a fixed name,
    so a stack file can point the planner at it whatever the world is).
    """
    if not (math.isfinite(resolution_m) and resolution_m > 0):
        raise ConfigError(f"--resolution must be a positive number of metres per cell, got {resolution_m}")
    if not (math.isfinite(padding_m) and padding_m >= 0):
        raise ConfigError(f"--padding must be a non-negative number of metres, got {padding_m}")
    world = load_world(world_file)
    occupancy = map_from_world(world, resolution_m=resolution_m, padding_m=padding_m)
    target = Path(output)
    if target.suffix not in (".yaml", ".yml"):
        target = target / f"{_safe_stem(world.name)}.yaml"
    return save_map(occupancy, target)


def _save(args: argparse.Namespace) -> int:
    try:
        yaml_path, pgm_path = save_world_map(args.world, args.output, args.resolution, args.padding)
    except ConfigError as exc:
        print(f"zendock map save: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"zendock map save: cannot write to {args.output}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    print(yaml_path)
    print(pgm_path)
    return 0


def build_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The flags of ``map save`` (shared by this module's main and the ``zendock`` CLI)."""
    parser.add_argument("--world", required=True, help="world file (deploy/worlds/*.yaml)")
    parser.add_argument(
        "-o",
        "--output",
        default=".",
        metavar="DIR|FILE.yaml",
        help="output directory, or the map's .yaml path (default: .)",
    )
    parser.add_argument("--resolution", type=float, default=0.05, help="metres per cell (default: 0.05)")
    parser.add_argument(
        "--padding",
        type=float,
        default=0.5,
        help="unknown margin around the world's bounds, metres (default: 0.5)",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser(argparse.ArgumentParser(prog="zendock map save")).parse_args(argv)
    return _save(args)


if __name__ == "__main__":
    sys.exit(main())
