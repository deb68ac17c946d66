"""``zendock param list|get|set NODE ...``: a running node's parameters, like ``ros2 param``.

Exit codes: 0 done, 1 the node did not answer, 2 refused (unknown name, not settable, bad value) with the
node's reason on one line. See :mod:`deploy.param`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from deploy.keys.verbs import Verb, bus_flags, dispatch
from deploy.param import run_param_get, run_param_list, run_param_set


def _dispatch(verb: Verb) -> Callable[[argparse.Namespace], int]:
    return dispatch("param", "param_verb", verb)


def register(subparsers: argparse._SubParsersAction) -> None:
    param = subparsers.add_parser(
        "param",
        help="list, get and set a running node's parameters (like ros2 param)",
        description="A running node's parameters. Only those its service marks runtime-settable change; "
        "list shows which and when a change applies. NODE is /<ns>/<name> as nodes list prints it, "
        "or a name in --namespace.",
        epilog="Exit codes: 0 done, 1 the node did not answer, 2 refused (the reason is printed).",
    )
    verbs = param.add_subparsers(dest="param_verb", metavar="VERB")
    verbs.required = True
    bus = bus_flags()

    p = verbs.add_parser("list", parents=[bus], help="every parameter: name, value, settable while running")
    p.add_argument("node", metavar="NODE")
    p.add_argument("--json", action="store_true", help="print JSON, with descriptions")
    p.set_defaults(func=_dispatch(lambda a, o: run_param_list(o, a.node, a.json, sys.stdout)))

    p = verbs.add_parser("get", parents=[bus], help="one parameter's value")
    p.add_argument("node", metavar="NODE")
    p.add_argument("name", metavar="NAME", help="parameter name (group.field for a nested one)")
    p.add_argument("--json", action="store_true", help="print JSON, with settable and description")
    p.set_defaults(func=_dispatch(lambda a, o: run_param_get(o, a.node, a.name, a.json, sys.stdout)))

    p = verbs.add_parser(
        "set",
        parents=[bus],
        help="change a runtime-settable parameter",
        description="Set NAME to VALUE (YAML, as -p NAME=VALUE at start-up), validated by the "
        "node as at start-up.",
    )
    p.add_argument("node", metavar="NODE")
    p.add_argument("name", metavar="NAME")
    p.add_argument("value", metavar="VALUE")
    p.set_defaults(func=_dispatch(lambda a, o: run_param_set(o, a.node, a.name, a.value, sys.stdout)))
