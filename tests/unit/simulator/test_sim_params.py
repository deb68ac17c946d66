"""The simulator's parameters: one model per component, strict, and the channel table built from them."""

from __future__ import annotations

from pathlib import Path

import pytest

from services.simulator.channels import channel_table
from services.simulator.params import Params
from shared import structs, topics
from shared.config_errors import ConfigError
from shared.runtime import ServiceOptions, load_params

WORLD = str(Path(__file__).resolve().parents[3] / "deploy" / "worlds" / "seed_room.yaml")


def _params(**overrides: object) -> Params:
    options = ServiceOptions(node_name="simulator", overrides={"world": WORLD, **overrides})
    params = load_params(Params, options)
    assert isinstance(params, Params)
    return params


def test_components_are_strict_and_frozen() -> None:
    params = _params()
    groups = [spec.name for spec in structs.fields(Params) if spec.group is not None]
    assert set(groups) == {
        "clock",
        "odom",
        "tf",
        "ground_truth",
        "localisation",
        "pacing",
        "drive",
        "lidar",
        "ultrasonic",
        "detection",
        "camera",
        "ir",
        "contact",
    }
    for name in groups:
        config = type(getattr(params, name)).__struct_config__
        assert config.forbid_unknown_fields and config.frozen, name


def test_dotted_overrides_reach_the_physics() -> None:
    params = _params(
        **{"lidar.noise_m": 0.02, "detection.source": "aruco", "localisation.error": [0.1, 0, 0]}
    )
    sim = params.sim_params(robot_index=2)
    assert sim.lidar.noise_m == 0.02 and sim.seed == 2 and sim.localisation_error.x == 0.1
    with pytest.raises(ConfigError, match="lidar.noise_m"):
        _params(**{"lidar.noise_m": float("inf")})


def test_one_check_per_value_also_for_direct_use() -> None:
    from services.simulator.sensors import UltrasonicParams

    with pytest.raises(ValueError, match="^range_max_m: 0.5 must exceed range_min_m 1.0"):
        UltrasonicParams(range_min_m=1.0, range_max_m=0.5)


def test_channel_table_rates_and_the_clock_last() -> None:
    table = channel_table(_params())
    rates = {ch.topic: ch.rate_hz for ch in table if ch.rate_hz is not None}
    assert rates == {
        topics.TF_STATIC: 1.0,
        topics.TF: 20.0,
        topics.ODOM: 20.0,
        topics.SCAN: 10.0,
        topics.ULTRASONIC: 20.0,
        topics.DETECTED_DOCK_POSE: 15.0,
        topics.CAMERA_INFO: 15.0,
        topics.CAMERA_IMAGE: 15.0,
        topics.DOCK_CONTACT: 20.0,
        topics.IR_DOCK: 20.0,
        topics.GROUND_TRUTH_POSE: 20.0,
        topics.CLOCK: 20.0,
    }
    assert table[-1].topic == topics.CLOCK
    assert [(ch.topic, ch.rate_hz) for ch in table if ch.on_demand] == [
        (topics.DETECTED_DOCK_POSE, 15.0),
        (topics.CAMERA_INFO, 15.0),
        (topics.CAMERA_IMAGE, 15.0),
        (topics.IR_DOCK, 20.0),
    ]
    aruco = channel_table(_params(**{"detection.source": "aruco", "camera.enabled": False}))
    assert [ch.rate_hz for ch in aruco if ch.topic == topics.DETECTED_DOCK_POSE] == [
        None
    ]  # only the queue drains
    assert not {topics.CAMERA_INFO, topics.CAMERA_IMAGE} & {ch.topic for ch in aruco}
