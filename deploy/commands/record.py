"""``zendock record``: the bus's messages into an MCAP file, like ``ros2 bag record``.

Usage::

    zendock record [-o FILE.mcap] [--duration S] [--world FILE] [--no-views] [--strict] [KEY...]
    zendock record --format ros2 [-o DIR] ...    # a ROS 2 bag (rosbag2 directory, MCAP, CDR)

With no KEY everything in the namespace is recorded. The world file (``--world``, default ``$ZENDOCK_WORLD``,
the stack's variable) is stored with the recording so ``zendock plot`` and viewers can draw the room. The file keeps the original msgpack payloads with
their type names (an exact replay) and Foxglove-schema channels (it opens in Foxglove or Lichtblick).
Ctrl-C (or ``--duration``) ends the recording; the summary then compares, per key, the messages recorded
with the publishers' sequence numbers and names every gap. Exit codes: 0 recorded, 1 no router (or,
with ``--strict``, messages were lost), 2 bad input. ``--format ros2`` writes what ``ros2 bag record -s
mcap`` writes (see :mod:`deploy.recording.ros2_bag`): ROS 2 tools read it, ``zendock replay`` plays it.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import signal
import sys
import threading
from pathlib import Path

from deploy.keys.connection import open_bus
from deploy.keys.errors import KeysError
from deploy.recording.bus import add_bus_flags, options_from
from deploy.recording.mcap_log import COMPRESSIONS
from deploy.recording.session import RecordRequest, record
from deploy.recording.summary import format_summary


def default_output(fmt: str = "zendock") -> Path:
    name = _dt.datetime.now().strftime("zendock_%Y%m%d_%H%M%S")
    return Path(name if fmt == "ros2" else f"{name}.mcap")


def _run(args: argparse.Namespace) -> int:
    if args.duration is not None and not args.duration > 0:
        print("zendock record: --duration must be positive", file=sys.stderr)
        return 2
    try:
        options = options_from(args)
        request = RecordRequest(
            output=Path(args.output) if args.output else default_output(args.format),
            keys=tuple(k.strip("/") for k in args.keys),
            duration_s=args.duration,
            world=Path(args.world) if args.world else None,
            views=not args.no_views,
            compression=args.compression,
            format=args.format,
        )
        if args.format == "ros2" and request.output.exists():
            print(f"zendock record: {request.output} exists; a ROS 2 bag is a new directory", file=sys.stderr)
            return 2
        stop = threading.Event()
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, lambda *_: stop.set())
        with open_bus(options) as session:
            print(f"recording to {request.output} (Ctrl-C to stop)", file=sys.stderr, flush=True)
            result = record(session, options.namespace, request, stop)
    except KeysError as exc:
        print(f"zendock record: {exc}", file=sys.stderr)
        return exc.exit_code
    except OSError as exc:
        print(f"zendock record: cannot write {args.output}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    print(format_summary(result.rows, result.duration_s))
    print(
        f"wrote {result.path} ({result.received} messages, {result.view_messages} Foxglove view messages; "
        f"writer backlog peaked at {result.stats.max_backlog})"
    )
    if result.skipped:
        left = ", ".join(f"{n} {t}" for t, n in sorted(result.skipped.items()))
        print(f"not in the ROS 2 bag (no ROS 2 type): {left}")
    return 1 if args.strict and result.lost else 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "record",
        help="record the bus into an MCAP file (like ros2 bag record)",
        description="Record keys into an MCAP file: msgpack payloads for exact replay, Foxglove channels for viewing.",
    )
    p.add_argument("keys", nargs="*", metavar="KEY", help="keys to record (wildcards allowed; default: all)")
    p.add_argument(
        "-o", "--output", metavar="FILE.mcap", help="output file (default zendock_<date>_<time>.mcap)"
    )
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    p.add_argument(
        "--world",
        metavar="FILE",
        default=os.environ.get("ZENDOCK_WORLD") or None,
        help="world file to store with the recording, for plots and viewers (default $ZENDOCK_WORLD)",
    )
    p.add_argument(
        "--no-views", action="store_true", help="record only the raw payloads, no Foxglove channels"
    )
    p.add_argument("--compression", choices=sorted(COMPRESSIONS), default="zstd", help="chunk compression")
    p.add_argument(
        "--format",
        choices=["zendock", "ros2"],
        default="zendock",
        help="zendock: msgpack payloads and Foxglove views in one MCAP file; ros2: a ROS 2 bag "
        "(rosbag2 directory, MCAP storage, CDR) for ros2 bag, Foxglove and rosbags",
    )
    p.add_argument(
        "--strict", action="store_true", help="exit 1 if the sequence numbers show any lost message"
    )
    add_bus_flags(p)
    p.set_defaults(func=_run)
