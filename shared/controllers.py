"""The docking controllers and dock detectors zendock ships, by name: the one table of each.

A name chosen here travels everywhere as it is: the docking service's ``controller`` parameter, the
perception service's ``dock_detector`` and the simulator's ``detection.source`` are typed by these tables;
the CLI's ``--controller`` and ``--detector`` take their choices and help from them; the contracts list
their values; trials choose their starts by the controller's ``starts``. What each controller *does* is
bound to its name in :mod:`services.docking.controllers`, which holds the implementations; a test holds
the two tables to the same names. Nothing outside these two modules compares a controller's name.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

#: The names as types: a parameter or option typed with these refuses any other value.
ControllerName = Literal["graceful", "seed", "ir"]
DetectorName = Literal["aruco", "synthetic"]
#: Where a campaign starts its robots: anywhere in the room, or within the dock's infrared field.
StartKind = Literal["room", "beacon"]


@dataclass(frozen=True)
class ControllerInfo:
    """What a user, a contract or a campaign needs to know of a docking controller."""

    name: ControllerName
    description: str
    #: The control loop's period: the approach laws were tuned at these rates.
    control_period_s: float
    #: Where trials start a robot that docks with it (``zendock trials --starts`` by default).
    starts: StartKind
    #: It drives from the dock's infrared beacon (``ir_dock``), with neither a map pose nor a camera.
    infrared: bool


@dataclass(frozen=True)
class DetectorInfo:
    """A source of ``detected_dock_pose``."""

    name: DetectorName
    description: str
    #: The perception service finds the dock in camera images (else the simulator reports it itself).
    camera: bool


CONTROLLERS: dict[str, ControllerInfo] = {
    info.name: info
    for info in (
        ControllerInfo(
            "graceful",
            "graceful approach law (smooth curve onto the dock's axis, perceiving while it drives), 20 Hz",
            0.05,
            "room",
            infrared=False,
        ),
        ControllerInfo(
            "seed",
            "the tutorial's three-step line approach (turn, drive, turn; bang-bang 0.08 m/s), 10 Hz",
            0.1,
            "room",
            infrared=False,
        ),
        ControllerInfo(
            "ir",
            "infrared docking from the dock's beacon, no map pose or camera (Kobuki's), 20 Hz",
            0.05,
            "beacon",
            infrared=True,
        ),
    )
}

DETECTORS: dict[str, DetectorInfo] = {
    info.name: info
    for info in (
        DetectorInfo(
            "aruco", "the perception service finds the dock's ArUco marker in camera images", camera=True
        ),
        DetectorInfo(
            "synthetic", "the simulator reports the true dock pose plus noise (no camera)", camera=False
        ),
    )
}

CONTROLLER_NAMES: tuple[ControllerName, ...] = get_args(ControllerName)
DETECTOR_NAMES: tuple[DetectorName, ...] = get_args(DetectorName)
DEFAULT_CONTROLLER: ControllerName = "graceful"


def controller(name: str) -> ControllerInfo:
    """The controller named ``name``; a ``ValueError`` lists the known ones."""
    try:
        return CONTROLLERS[name]
    except KeyError:
        raise ValueError(f"no docking controller {name!r} (one of: {', '.join(CONTROLLERS)})") from None


def detector(name: str) -> DetectorInfo:
    """The detector named ``name``; a ``ValueError`` lists the known ones."""
    try:
        return DETECTORS[name]
    except KeyError:
        raise ValueError(f"no dock detector {name!r} (one of: {', '.join(DETECTORS)})") from None


def choices_help(table: dict[str, ControllerInfo] | dict[str, DetectorInfo]) -> str:
    """``name: description; ...`` for an option's help."""
    return "; ".join(f"{name}: {info.description}" for name, info in table.items())
