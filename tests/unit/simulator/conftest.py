"""Small worlds and noise-free parameters for the simulator's unit tests (as fixtures)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from services.simulator.physics import SimParams
from services.simulator.sensors import FiducialCameraParams, LidarParams, UltrasonicParams
from shared.world import World, parse_world

_WORLDS = Path(__file__).resolve().parents[3] / "deploy" / "worlds"

_QUIET = SimParams(
    lidar=LidarParams(noise_m=0.0),
    ultrasonic=UltrasonicParams(noise_m=0.0),
    camera=FiducialCameraParams(position_sigma_m=0.0, yaw_sigma_rad=0.0),
)


def _open_world(**extra: Any) -> World:
    """A 10 m x 10 m room, robot at the origin facing +x, plus whatever ``extra`` adds."""
    data: dict[str, Any] = {
        "name": "test",
        "bounds": [-5.0, -5.0, 5.0, 5.0],
        "robot": {"start": [0.0, 0.0, 0.0]},
    }
    data.update(extra)
    return parse_world(data)


def _dock_world(**extra: Any) -> World:
    """A dock at the origin facing +x (its body from x=0.2 to 0.4); the robot starts 1 m short of it."""
    return _open_world(
        docks=[{"id": "home", "pose": [0.0, 0.0, 0.0]}], robot={"start": [-1.0, 0.0, 0.0]}, **extra
    )


@pytest.fixture
def quiet() -> SimParams:
    """Sensors without noise, for exact expectations."""
    return _QUIET


@pytest.fixture
def worlds_dir() -> Path:
    return _WORLDS


@pytest.fixture
def open_world() -> Callable[..., World]:
    return _open_world


@pytest.fixture
def dock_world() -> Callable[..., World]:
    return _dock_world
