"""``zendock plot``: a recording as a picture: room, plan, driven path, sonar hits, battery over time.

Usage::

    zendock plot FILE.mcap -o FILE.png [--world FILE] [--namespace NS]

The world drawn is ``--world``, else the one stored with the recording, else the recorded map. Exit
codes: 0 written, 1 cannot write, 2 bad input.
"""

from __future__ import annotations

import argparse
import sys

from shared.config_errors import ConfigError


def _run(args: argparse.Namespace) -> int:
    from deploy.plotting import plot_picture  # noqa: PLC0415 - matplotlib only when plotting
    from deploy.recording.reading import Recording  # noqa: PLC0415
    from deploy.recording.run_data import run_picture  # noqa: PLC0415
    from shared.world import load_world  # noqa: PLC0415

    try:
        world = load_world(args.world) if args.world else None
        with Recording(args.file) as recording:
            picture = run_picture(recording, namespace=args.namespace, world=world)
    except ConfigError as exc:
        print(f"zendock plot: {exc}", file=sys.stderr)
        return 2
    try:
        path = plot_picture(picture, args.output, dpi=args.dpi)
    except OSError as exc:
        print(f"zendock plot: cannot write {args.output}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    print(
        f"{path}: {len(picture.trajectory)} poses, {len(picture.planned_paths)} plan(s), "
        f"{len(picture.sonar_hits)} sonar hits, {len(picture.battery)} battery readings"
    )
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "plot",
        help="draw a recording: room, plan, driven path, sonar hits, battery",
        description="Draw an MCAP recording as a PNG: walls, glass, dock, planned path, trajectory, sonar hits, battery.",
    )
    p.add_argument("file", metavar="FILE.mcap", help="a recording made by zendock record")
    p.add_argument("-o", "--output", required=True, metavar="FILE.png", help="picture to write")
    p.add_argument("--world", metavar="FILE", help="world file to draw (default: the one in the recording)")
    p.add_argument(
        "--namespace", default=None, metavar="NS", help="robot to draw (default: the recording's namespace)"
    )
    p.add_argument("--dpi", type=int, default=120, help="resolution (default 120)")
    p.set_defaults(func=_run)
