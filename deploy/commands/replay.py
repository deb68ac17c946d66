"""``zendock replay``: a recording back onto the bus with its original timing, like ``ros2 bag play``.

Usage::

    zendock replay FILE.mcap|ROS2_BAG_DIR [--rate R] [--loop] [--keys KEY...] [--remap-namespace NS]

Publishes the recorded msgpack payloads on their keys (``application/msgpack;<type>``), spaced as they
arrived, ``R`` times as fast. ``--remap-namespace`` moves the keys from the recording's namespace to NS.
Ctrl-C stops. Exit codes: 0 done, 1 no router, 2 bad input.
"""

from __future__ import annotations

import argparse
import signal
import sys
from typing import TYPE_CHECKING

from deploy.keys.connection import open_bus
from deploy.keys.errors import KeysError
from deploy.recording.bus import add_bus_flags, options_from
from deploy.recording.reading import Recording
from deploy.recording.replay import Replayer
from shared.config_errors import ConfigError
from shared.names import normalise_namespace

if TYPE_CHECKING:
    from deploy.recording.ros2_bag import Ros2BagRecording


def open_recording(path: str) -> Recording | Ros2BagRecording:
    """zendock's MCAP file, or a ROS 2 bag directory (its CDR turned back into zendock's messages)."""
    from deploy.recording.ros2_bag import Ros2BagRecording, is_ros2_bag  # noqa: PLC0415 - rosbags only for bags

    if not is_ros2_bag(path):
        return Recording(path)
    bag = Ros2BagRecording(path)
    if bag.unknown_types:
        print(
            f"zendock replay: left out, no zendock message has the type: {', '.join(bag.unknown_types)}",
            file=sys.stderr,
        )
    return bag


def _run(args: argparse.Namespace) -> int:
    if not args.rate > 0:
        print("zendock replay: --rate must be positive", file=sys.stderr)
        return 2
    try:
        target = None if args.remap_namespace is None else normalise_namespace(args.remap_namespace)
    except ValueError as exc:
        print(f"zendock replay: --remap-namespace: {exc}", file=sys.stderr)
        return 2
    try:
        options = options_from(args)
        with open_recording(args.file) as recording, open_bus(options) as session:
            replayer = Replayer(
                session, recording, rate=args.rate, loop=args.loop, keys=args.keys or (), namespace=target
            )
            if not replayer.keys:
                print(
                    f"zendock replay: no recorded key matches {args.keys}; recorded: "
                    f"{', '.join(sorted(recording.raw_keys())) or 'none'}",
                    file=sys.stderr,
                )
                return 2
            for sig in (signal.SIGINT, signal.SIGTERM):
                signal.signal(sig, lambda *_: replayer.stop())
            print(
                f"replaying {len(replayer.keys)} key(s) from {args.file} at x{args.rate:g}"
                f"{' in a loop' if args.loop else ''} (Ctrl-C to stop)",
                file=sys.stderr,
                flush=True,
            )
            stats = replayer.run()
    except KeysError as exc:
        print(f"zendock replay: {exc}", file=sys.stderr)
        return exc.exit_code
    except ConfigError as exc:
        print(f"zendock replay: {exc}", file=sys.stderr)
        return 2
    print(f"published {stats.published} messages on {len(stats.per_key)} key(s) in {stats.passes} pass(es)")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "replay",
        help="publish a recording back onto the bus (like ros2 bag play)",
        description="Publish an MCAP recording's keys back onto the bus with their original timing.",
    )
    p.add_argument("file", metavar="FILE.mcap", help="a recording made by zendock record")
    p.add_argument("--rate", type=float, default=1.0, metavar="R", help="play R times as fast (default 1)")
    p.add_argument("--loop", action="store_true", help="start over at the end, until stopped")
    p.add_argument(
        "--keys",
        nargs="+",
        metavar="KEY",
        help="replay only these keys (full or relative to the recording's namespace)",
    )
    p.add_argument(
        "--remap-namespace", metavar="NS", help="publish in namespace NS instead of the recorded one"
    )
    add_bus_flags(p)
    p.set_defaults(func=_run)
