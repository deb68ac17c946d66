"""One registry of docking controllers: the shared table and the implementations name the same ones."""

from __future__ import annotations

from pathlib import Path

import pytest

from services.docking.controllers import REGISTRY
from services.docking.dock_db import load_dock_db
from services.docking.docking_run import DockingRun, DockRequest
from services.docking.ir_run import IrDockingRun
from services.docking.params import Params
from shared import structs
from shared.config_errors import ConfigError
from shared.controllers import CONTROLLER_NAMES, CONTROLLERS, DETECTOR_NAMES, DETECTORS, controller, detector

SEED_ROOM = str(Path(__file__).resolve().parents[3] / "deploy" / "worlds" / "seed_room.yaml")


def test_every_named_controller_has_one_implementation_and_one_description() -> None:
    assert tuple(CONTROLLERS) == CONTROLLER_NAMES
    assert tuple(REGISTRY) == CONTROLLER_NAMES
    for name, entry in REGISTRY.items():
        assert entry.info is CONTROLLERS[name]
        assert entry.info.description and entry.info.control_period_s > 0
    assert tuple(DETECTORS) == DETECTOR_NAMES


def test_an_unknown_name_is_refused_with_the_known_ones() -> None:
    with pytest.raises(ValueError, match="one of: graceful, seed, ir"):
        controller("gracefull")
    with pytest.raises(ValueError, match="one of: aruco, synthetic"):
        detector("april")
    with pytest.raises(ConfigError, match="controller: invalid enum value 'gracefull'"):
        structs.validate(Params, {"dock_database": SEED_ROOM, "controller": "gracefull"}, "params")


@pytest.mark.parametrize("name", CONTROLLER_NAMES)
def test_each_controller_builds_its_own_docking_run(name: str) -> None:
    params = structs.validate(Params, {"dock_database": SEED_ROOM, "controller": name}, "params")
    database = load_dock_db(SEED_ROOM)
    run = params.docking_controller.docking_run(params, DockRequest(), database, None)
    assert isinstance(run, IrDockingRun if CONTROLLERS[name].infrared else DockingRun)
    assert params.approach_controller() is not params.approach_controller()  # a fresh law for each run
