"""What stack a test gets: the ``@pytest.mark.zendock(...)`` marker and the ``--zendock-*`` options, read into one
:class:`StackConfig`.

Kept apart from the fixtures and free of pytest and of the launcher, so reading a marker is a pure function
the plugin's unit tests check directly, and a typo in a marker fails the test with one line naming the
argument (not a stack that starts and then misbehaves).

Precedence: the closest marker wins over a class's or a module's; the command line wins over every marker
(``--zendock-rtf`` slows every stack of a run on a loaded machine; ``--zendock-service`` puts a user's
replacement into every stack, zendock's own end-to-end tests included).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from deploy.paths import REPO_ROOT

if TYPE_CHECKING:
    from deploy.replacements import Replacement
from shared.controllers import DEFAULT_CONTROLLER, ControllerName, DetectorName
from shared.controllers import controller as find_controller
from shared.controllers import detector as find_detector

#: The stack the fixture brings up, and where ``world="seed_room"`` is looked up.
DEFAULT_STACK = REPO_ROOT / "deploy" / "stack.yaml"
WORLDS_DIR = REPO_ROOT / "deploy" / "worlds"
#: The marker's arguments (anything else is a mistake, reported as such).
MARKER_ARGUMENTS = (
    "world",
    "rtf",
    "detector",
    "controller",
    "seed",
    "localisation_error",
    "services",
    "healthy_timeout_s",
)


@dataclass(frozen=True)
class StackConfig:
    """One test's stack. ``rtf`` 4 by default: fast enough for a test, slow enough for two cores."""

    world: Path = WORLDS_DIR / "seed_room.yaml"
    rtf: str = "4"
    detector: DetectorName = "aruco"
    controller: ControllerName = DEFAULT_CONTROLLER
    seed: int = 0
    #: map->odom error of the simulated localisation (x_m, y_m, yaw_rad).
    localisation_error: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: ``NAME=COMMAND`` replacements (see :mod:`deploy.replacements`), in order, one per service.
    #: ``services=`` and ``--zendock-service``: zendock's services replaced by a user's programs.
    services: tuple[Replacement, ...] = ()
    #: How long the stack has to become healthy (wall seconds).
    healthy_timeout_s: float = 90.0

    def environment(self, endpoint: str, project_dir: Path) -> dict[str, str]:
        """The stack file's variables (``deploy/stack.yaml``'s header lists them), as ``zendock demo`` sets them."""
        from deploy.demo import DemoOptions, stack_environment  # noqa: PLC0415 - only when a stack starts

        options = DemoOptions(
            world=self.world,
            controller=self.controller,
            detector=self.detector,
            rtf=self.rtf,
            seed=self.seed,
            localisation_error=self.localisation_error,
        )
        return stack_environment(options, endpoint, project_dir)


def shipped_worlds() -> list[str]:
    return sorted(p.stem for p in WORLDS_DIR.glob("*.yaml"))


def resolve_world(value: str | Path, rootdir: Path) -> Path:
    """A shipped world's name (``seed_room``) or a world file (relative to ``rootdir``), as an absolute path."""
    text = str(value)
    if "/" not in text and not text.endswith((".yaml", ".yml")):
        path = WORLDS_DIR / f"{text}.yaml"
        if not path.is_file():
            raise ValueError(
                f"world={text!r}: no shipped world of that name (one of: {', '.join(shipped_worlds())}), "
                "nor a path to a world file"
            )
        return path
    path = Path(text) if Path(text).is_absolute() else rootdir / text
    if not path.is_file():
        raise ValueError(f"world={text!r}: {path} is not a file")
    return path.resolve()


def parse_rtf(value: object) -> str:
    """A real-time factor as the stack takes it: a positive number, or ``max``."""
    text = str(value).strip()
    if text == "max":
        return text
    try:
        number = float(text)
    except ValueError:
        number = math.nan
    if not (math.isfinite(number) and number > 0):
        raise ValueError(f"rtf={value!r}: expected a positive number or 'max'")
    return text


def parse_services(services: object, where: str) -> list[Replacement]:
    """``{"docking": "python my_docking.py"}`` (a marker's) or ``["docking=python my_docking.py"]`` (options')
    as checked replacements; raises ``ValueError`` naming the problem."""
    from deploy.replacements import (  # noqa: PLC0415 - the stack file model is slow to import
        check_unique,
        parse_replacement,
    )

    if isinstance(services, Mapping):
        texts = [f"{name}={command}" for name, command in services.items()]
    elif isinstance(services, Iterable) and not isinstance(services, str | bytes):
        texts = [str(text) for text in services]
    else:
        raise ValueError(f"{where}: services must be a dict of service name to command, got {services!r}")
    replacements = []
    for text in texts:
        try:
            replacements.append(parse_replacement(text))
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
    return check_unique(replacements, option=where)


def merge_markers(marker_kwargs: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Markers' arguments, farthest first (module, class, function): a closer one overrides a farther one."""
    merged: dict[str, Any] = {}
    for kwargs in marker_kwargs:
        unknown = sorted(set(kwargs) - set(MARKER_ARGUMENTS))
        if unknown:
            raise ValueError(
                f"@pytest.mark.zendock: unknown argument(s) {', '.join(unknown)} "
                f"(known: {', '.join(MARKER_ARGUMENTS)})"
            )
        merged.update(kwargs)
    return merged


def stack_config(
    marker: Mapping[str, Any],
    cli_services: Sequence[str] = (),
    cli_rtf: str | None = None,
    rootdir: Path = REPO_ROOT,
) -> StackConfig:
    """The stack for one test: the (merged) marker's arguments, then the command line's."""
    defaults = StackConfig()
    world = resolve_world(marker["world"], rootdir) if "world" in marker else defaults.world
    rtf = parse_rtf(cli_rtf if cli_rtf is not None else marker.get("rtf", defaults.rtf))
    detector = find_detector(str(marker.get("detector", defaults.detector))).name
    controller = find_controller(str(marker.get("controller", defaults.controller))).name
    error = tuple(float(v) for v in marker.get("localisation_error", defaults.localisation_error))
    if len(error) != 3:
        raise ValueError(f"localisation_error={marker['localisation_error']!r}: expected (x_m, y_m, yaw_rad)")
    timeout = float(marker.get("healthy_timeout_s", defaults.healthy_timeout_s))
    if not timeout > 0:
        raise ValueError(f"healthy_timeout_s={timeout!r}: expected a positive number of seconds")
    services = {
        r.name: r for r in parse_services(marker.get("services", {}), "@pytest.mark.zendock(services=...)")
    }
    services.update(
        (r.name, r) for r in parse_services(cli_services, "--zendock-service")
    )  # the command line wins
    return StackConfig(
        world=world,
        rtf=rtf,
        detector=detector,
        controller=controller,
        seed=int(marker.get("seed", defaults.seed)),
        localisation_error=(error[0], error[1], error[2]),
        services=tuple(services.values()),
        healthy_timeout_s=timeout,
    )
