"""Docking parameters decide the controller's settings in one place."""

from __future__ import annotations

from pathlib import Path

from services.docking.approach_control import GracefulApproach, SeedApproach
from services.docking.params import Params
from shared import structs

SEED_ROOM = str(Path(__file__).resolve().parents[3] / "deploy" / "worlds" / "seed_room.yaml")


def test_graceful_waits_for_detection_and_hands_over_from_navigation() -> None:
    params = structs.validate(Params, {"dock_database": SEED_ROOM, "handover_distance_m": 0.4}, "params")
    config = params.docking_config()
    assert params.docking_controller.perceives_while_driving and isinstance(
        params.approach_controller(), GracefulApproach
    )
    assert config.wait_for_detection and config.continuous_perception
    assert config.handover_distance_m == 0.4
    assert config.max_control_pose_age_s == params.max_control_pose_age_s
    assert params.undock_config().staging_offset_m == params.staging_offset_m


def test_the_line_approach_neither_waits_nor_hands_over() -> None:
    params = structs.validate(Params, {"dock_database": SEED_ROOM, "controller": "seed"}, "params")
    config = params.docking_config()
    assert not params.docking_controller.perceives_while_driving and isinstance(
        params.approach_controller(), SeedApproach
    )
    assert not config.wait_for_detection and not config.continuous_perception
    assert config.handover_distance_m is None and config.max_control_pose_age_s is None


def test_zero_handover_distance_means_navigation_always_stages_first() -> None:
    params = structs.validate(Params, {"dock_database": SEED_ROOM, "handover_distance_m": 0}, "params")
    config = params.docking_config()
    assert config.handover_distance_m is None
