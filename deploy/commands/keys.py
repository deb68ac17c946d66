"""``zendock keys``: list, echo, measure and publish on the bus's keys, like ``ros2 topic``.

Usage::

    zendock keys list [-t] [-v] [-a]
    zendock keys echo KEY [--once | --times N] [--timeout S] [--field a.b.0] [--csv | --raw] [--array-limit N]
    zendock keys hz KEY... [-w WINDOW] [--sim-time] [--duration S] [--json]
    zendock keys bw KEY... [-w WINDOW] [--duration S] [--json]
    zendock keys delay KEY... [-w WINDOW] [--sim-time] [--duration S] [--json]
    zendock keys info KEY
    zendock keys pub KEY [TYPE] ['YAML'] [--rate HZ] [--once | --times N] [--wait-matching S] [-q]

Every verb takes ``--connect ENDPOINT`` (repeatable; env ``ZENDOCK_CONNECT``/``ZENOH_CONNECT``; default
tcp/127.0.0.1:7447), ``--namespace NS`` (env ``ZENDOCK_NAMESPACE``) and ``--connect-timeout S``. Keys are
relative to the namespace; a leading ``/`` is the same as none (``/cmd_vel`` == ``cmd_vel``). Exit codes:
0 done, 1 nothing answered (no router, no message, unknown key), 2 bad input (nothing was sent).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from deploy.keys.bw import run_bw
from deploy.keys.connection import BusOptions
from deploy.keys.delay import run_delay
from deploy.keys.echo import EchoRequest, run_echo
from deploy.keys.hz import run_hz
from deploy.keys.info import run_info
from deploy.keys.listing import ListFormat, run_list
from deploy.keys.monitor import MonitorRequest
from deploy.keys.pub import (
    DEFAULT_RATE_HZ,
    DEFAULT_WAIT_MATCHING_S,
    PubRequest,
    run_pub,
    split_type_and_values,
)
from deploy.keys.render import DEFAULT_ARRAY_LIMIT, EchoFormat
from deploy.keys.stats import DEFAULT_BW_WINDOW, DEFAULT_RATE_WINDOW
from deploy.keys.verbs import Verb, bus_flags, dispatch


def _monitor_flags(sim_time: bool, default_window: int) -> argparse.ArgumentParser:
    flags = argparse.ArgumentParser(add_help=False)
    flags.add_argument("keys", nargs="+", metavar="KEY", help="key(s) to watch; wildcards allowed")
    flags.add_argument(
        "-w",
        "--window",
        type=int,
        default=default_window,
        help=f"messages in the statistics window (default {default_window})",
    )
    if sim_time:
        flags.add_argument(
            "--sim-time",
            action="store_true",
            help="measure on the namespace's clock key instead of the wall clock",
        )
    flags.add_argument("--duration", type=float, default=None, metavar="S", help="stop after S seconds")
    flags.add_argument(
        "--json",
        action="store_true",
        help="print only a JSON summary at the end (for scripts and benchmarks)",
    )
    return flags


def _dispatch(verb: Verb) -> Callable[[argparse.Namespace], int]:
    return dispatch("keys", "keys_verb", verb)


def _list(args: argparse.Namespace, options: BusOptions) -> int:
    return run_list(
        options,
        ListFormat(show_types=args.show_types, verbose=args.verbose, include_hidden=args.include_hidden),
        sys.stdout,
    )


def _echo(args: argparse.Namespace, options: BusOptions) -> int:
    fmt = EchoFormat(
        field=args.field or "",
        csv=args.csv,
        raw=args.raw,
        array_limit=args.array_limit,
        show_key=args.show_key,
        show_sequence=args.show_sequence,
    )
    count = 1 if args.once else args.times
    return run_echo(options, EchoRequest(args.key, fmt, count, args.timeout), sys.stdout)


def _monitor_request(args: argparse.Namespace) -> MonitorRequest:
    return MonitorRequest(
        keys=tuple(args.keys),
        window=args.window,
        sim_time=getattr(args, "sim_time", False),
        duration_s=args.duration,
        json=args.json,
    )


def _hz(args: argparse.Namespace, options: BusOptions) -> int:
    return run_hz(options, _monitor_request(args), sys.stdout)


def _bw(args: argparse.Namespace, options: BusOptions) -> int:
    return run_bw(options, _monitor_request(args), sys.stdout)


def _delay(args: argparse.Namespace, options: BusOptions) -> int:
    return run_delay(options, _monitor_request(args), sys.stdout)


def _info(args: argparse.Namespace, options: BusOptions) -> int:
    return run_info(options, args.key, sys.stdout)


def _pub(args: argparse.Namespace, options: BusOptions) -> int:
    type_name, values = split_type_and_values(args.type_and_values)
    request = PubRequest(
        key=args.key,
        type_name=type_name,
        values_yaml=values,
        rate_hz=args.rate,
        times=1 if args.once else args.times,
        wait_matching_s=args.wait_matching,
        quiet=args.quiet,
    )
    return run_pub(options, request, sys.stdout)


def register(subparsers: argparse._SubParsersAction) -> None:
    keys = subparsers.add_parser(
        "keys",
        help="list, echo, measure and publish on keys (like ros2 topic)",
        description="List, echo, measure and publish on the bus's keys, like ros2 topic.",
        epilog=(
            "Keys are relative to --namespace; a leading '/' means the same as none. Exit codes: 0 done, "
            "1 nothing answered (no router, no message, unknown key), 2 bad input (nothing was sent)."
        ),
    )
    verbs = keys.add_subparsers(dest="keys_verb", metavar="VERB")
    verbs.required = True
    bus = bus_flags()

    p = verbs.add_parser(
        "list",
        parents=[bus],
        help="keys in use, from the services' liveliness tokens",
        description="Keys in use; services and actions are marked. --namespace limits the list.",
    )
    p.add_argument("-t", "--show-types", action="store_true", help="show each key's type")
    p.add_argument("-v", "--verbose", action="store_true", help="show types and the nodes on each key")
    p.add_argument(
        "-a",
        "--include-hidden",
        "--include-hidden-topics",
        dest="include_hidden",
        action="store_true",
        help="also list hidden keys: those with a part starting with _ (an action's _action/... parts)",
    )
    p.set_defaults(func=_dispatch(_list))

    p = verbs.add_parser(
        "echo",
        parents=[bus],
        help="print messages on a key",
        description="Print messages on KEY as YAML-like blocks separated by '---'.",
    )
    p.add_argument("key", metavar="KEY", help="key to print; wildcards (*, **) allowed")
    count = p.add_mutually_exclusive_group()
    count.add_argument("--once", action="store_true", help="print one message and exit")
    count.add_argument("--times", type=int, metavar="N", help="print N messages and exit")
    p.add_argument(
        "--timeout", type=float, metavar="S", help="give up after S seconds (exit 1 if nothing came)"
    )
    p.add_argument("--field", metavar="PATH", help="print only this field: dotted path, list items by index")
    style = p.add_mutually_exclusive_group()
    style.add_argument("--csv", action="store_true", help="one comma-separated line per message")
    style.add_argument("--raw", action="store_true", help="print payloads as hex, undecoded")
    p.add_argument(
        "--array-limit",
        type=int,
        default=DEFAULT_ARRAY_LIMIT,
        metavar="N",
        help=f"print at most N items of an array (default {DEFAULT_ARRAY_LIMIT}; 0: all)",
    )
    p.add_argument("--show-key", action="store_true", help="precede each message by its key and type")
    p.add_argument("--show-sequence", action="store_true", help="also show the publisher's sequence number")
    p.set_defaults(func=_dispatch(_echo))

    p = verbs.add_parser(
        "hz",
        parents=[bus, _monitor_flags(True, DEFAULT_RATE_WINDOW)],
        help="message rate on keys",
        description="Average rate, min, max and std dev of the "
        "intervals between messages, printed every second.",
    )
    p.set_defaults(func=_dispatch(_hz))

    p = verbs.add_parser(
        "bw",
        parents=[bus, _monitor_flags(False, DEFAULT_BW_WINDOW)],
        help="bandwidth used by keys",
        description="Bytes per second and message sizes, printed every second.",
    )
    p.set_defaults(func=_dispatch(_bw))

    p = verbs.add_parser(
        "delay",
        parents=[bus, _monitor_flags(True, DEFAULT_RATE_WINDOW)],
        help="receive time minus header.stamp",
        description="Delay between header.stamp and receipt (wall clock, or --sim-time).",
    )
    p.set_defaults(func=_dispatch(_delay))

    p = verbs.add_parser(
        "info",
        parents=[bus],
        help="type and nodes on a key",
        description="Type, publishers, subscribers and servers on KEY (wildcards allowed).",
    )
    p.add_argument("key", metavar="KEY")
    p.set_defaults(func=_dispatch(_info))

    p = verbs.add_parser(
        "pub",
        parents=[bus],
        help="publish a message on a key",
        description="Publish TYPE (looked up from the key's tokens when omitted) built from "
        "YAML values merged over the type's defaults, e.g. "
        "zendock keys pub cmd_vel '{linear: {x: 0.2}}' --once.",
    )
    p.add_argument("key", metavar="KEY")
    p.add_argument(
        "type_and_values",
        nargs="*",
        metavar="ARG",
        help="[TYPE] [VALUES]: message type (e.g. geometry_msgs/msg/Twist) and YAML values",
    )
    p.add_argument(
        "-r",
        "--rate",
        type=float,
        default=DEFAULT_RATE_HZ,
        metavar="HZ",
        help=f"publishing rate (default {DEFAULT_RATE_HZ:g} Hz)",
    )
    count = p.add_mutually_exclusive_group()
    count.add_argument("-1", "--once", action="store_true", help="publish one message and exit")
    count.add_argument("-t", "--times", type=int, metavar="N", help="publish N messages and exit")
    p.add_argument(
        "--wait-matching",
        type=float,
        default=DEFAULT_WAIT_MATCHING_S,
        metavar="S",
        help="with --once/--times, wait up to S seconds for a subscriber first "
        f"(default {DEFAULT_WAIT_MATCHING_S:g})",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="do not print each message")
    p.set_defaults(func=_dispatch(_pub))
