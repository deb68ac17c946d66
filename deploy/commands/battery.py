"""``zendock battery get|set``: the simulated battery's charge from the command line (see
:mod:`deploy.battery`).

Exit codes: 0 done, 1 nothing answered, 2 refused or a bad argument (the reason on one line).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from deploy.arg_types import reporting
from deploy.battery import parse_level, parse_scale, run_battery_get, run_battery_set
from deploy.keys.verbs import Verb, bus_flags, dispatch


def _dispatch(verb: Verb) -> Callable[[argparse.Namespace], int]:
    return dispatch("battery", "battery_verb", verb)


def register(subparsers: argparse._SubParsersAction) -> None:
    battery = subparsers.add_parser(
        "battery",
        help="read or set the simulated battery's charge",
        description="The simulated battery of --namespace: its charge, status and the knobs in force "
        "(get), or a new charge and knobs (set). With 'zendock param set docking auto_dock false' a "
        "program of your own can dock from a low battery without zendock reacting to it too.",
        epilog="Exit codes: 0 done, 1 no battery answered, 2 refused (the reason is printed).",
    )
    verbs = battery.add_subparsers(dest="battery_verb", metavar="VERB")
    verbs.required = True
    bus = bus_flags()

    p = verbs.add_parser("get", parents=[bus], help="charge, status, voltage, current and knobs")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_dispatch(lambda a, o: run_battery_get(o, a.json, sys.stdout)))

    p = verbs.add_parser(
        "set",
        parents=[bus],
        help="set the charge (0.2 or 20%%) and the knobs",
        description="Set what is given; the rest stays as it is.",
    )
    p.add_argument("level", nargs="?", type=reporting(parse_level), metavar="LEVEL", help="0.2 or 20%%")
    p.add_argument("--drain-scale", type=reporting(parse_scale), metavar="X", help="drain X times faster")
    p.add_argument("--charge-scale", type=reporting(parse_scale), metavar="X", help="charge X times faster")
    freeze = p.add_mutually_exclusive_group()
    freeze.add_argument("--freeze", dest="frozen", action="store_const", const=True, help="hold the charge")
    freeze.add_argument("--thaw", dest="frozen", action="store_const", const=False, help="let it move again")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(
        func=_dispatch(
            lambda a, o: run_battery_set(
                o, a.level, a.drain_scale, a.charge_scale, a.frozen, a.json, sys.stdout
            )
        )
    )
