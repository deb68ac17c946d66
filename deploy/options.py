"""Options several commands share, each defined once: where the bus is, which controller, which detector,
where run directories go."""

from __future__ import annotations

import argparse
from pathlib import Path

from shared.controllers import CONTROLLERS, DEFAULT_CONTROLLER, DETECTORS, DetectorName, choices_help
from shared.session import DEFAULT_ROUTER_ENDPOINT

#: How long a command waits to reach the router before it says so.
DEFAULT_CONNECT_TIMEOUT_S = 3.0

#: A parser or an argument group.
_Adds = argparse._ActionsContainer


def add_connect_option(parser: _Adds) -> None:
    """``--connect ENDPOINT`` (repeatable): where a command's Zenoh session connects."""
    parser.add_argument(
        "--connect",
        action="append",
        metavar="ENDPOINT",
        help="Zenoh router endpoint, repeatable (env ZENDOCK_CONNECT or ZENOH_CONNECT; "
        f"default {DEFAULT_ROUTER_ENDPOINT})",
    )


def add_bus_options(parser: _Adds) -> None:
    """Where a command finds the bus: ``--connect``, ``--namespace`` and ``--connect-timeout``."""
    add_connect_option(parser)
    parser.add_argument(
        "--namespace",
        default=None,
        metavar="NS",
        help="robot namespace keys are relative to (env ZENDOCK_NAMESPACE)",
    )
    parser.add_argument(
        "--connect-timeout",
        type=float,
        default=DEFAULT_CONNECT_TIMEOUT_S,
        metavar="S",
        help=f"give up reaching the router after S seconds (default {DEFAULT_CONNECT_TIMEOUT_S:g})",
    )


def add_runs_dir_option(parser: _Adds, what: str = "the run directory goes") -> None:
    """``--runs-dir DIR``: where ``what`` (default: runs/ in the repository)."""
    parser.add_argument(
        "--runs-dir",
        type=Path,
        default=None,
        metavar="DIR",
        help=f"where {what} (default: runs/ in the repository)",
    )


def add_standby_option(parser: _Adds) -> None:
    """``--standby``: the supervisor keeps a warm standby per restartable service (:mod:`deploy.standby`)."""
    parser.add_argument(
        "--standby",
        action="store_true",
        help="keep a warm standby of each restartable zendock service, its imports done: a killed service "
        "is back in a fraction of the cold start, for a second process's memory per service",
    )


def add_controller_option(parser: _Adds) -> None:
    """``--controller NAME``: the docking controller, one of :data:`shared.controllers.CONTROLLERS`."""
    parser.add_argument(
        "--controller",
        choices=list(CONTROLLERS),
        default=DEFAULT_CONTROLLER,
        help=f"docking controller ({choices_help(CONTROLLERS)})",
    )


def add_detector_option(parser: _Adds, default: DetectorName) -> None:
    """``--detector NAME``: how robots find their dock, one of :data:`shared.controllers.DETECTORS`."""
    parser.add_argument(
        "--detector",
        choices=list(DETECTORS),
        default=default,
        help=f"dock detector ({choices_help(DETECTORS)})",
    )
