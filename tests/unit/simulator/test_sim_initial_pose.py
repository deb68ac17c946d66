"""An initial pose is judged against the lidar, as a scan-matching localiser would judge it."""

from __future__ import annotations

import numpy as np
import pytest

from services.simulator.localisation import scan_agreement
from services.simulator.params import LocalisationParams
from services.simulator.physics import Robot
from shared.geometry import Pose2D
from shared.world import load_world

SEED_ROOM = "deploy/worlds/seed_room.yaml"
#: The simulator's default: an initial pose on which fewer beams agree is refused.
MIN_AGREEMENT = LocalisationParams().initial_pose_min_agreement


def test_the_map_origin_disagrees_with_the_scans_of_a_robot_metres_from_it() -> None:
    """Nav2 scripts that set no initial pose publish zeros; the seed room's robot starts at (1.8, 4.2)."""
    robot = Robot(load_world(SEED_ROOM))
    assert robot.pose.distance_to(Pose2D()) > 4.0
    assert robot.lidar_agreement(Pose2D()) < 0.1 < MIN_AGREEMENT


@pytest.mark.parametrize(
    "offset",
    [Pose2D(0.3, -0.2, 0.0), Pose2D(0.0, 0.0, 0.3), Pose2D(0.5, 0.0, 0.0), Pose2D(0.3, -0.2, 0.4)],
)
def test_an_estimate_a_localiser_would_pull_in_agrees(offset: Pose2D) -> None:
    robot = Robot(load_world(SEED_ROOM))
    truth = robot.pose
    estimate = Pose2D(truth.x + offset.x, truth.y + offset.y, truth.yaw + offset.yaw)
    assert robot.lidar_agreement(estimate) > MIN_AGREEMENT
    assert robot.lidar_agreement(truth) == 1.0


def test_agreement_counts_beams_clear_in_both_or_near_in_both() -> None:
    inf = np.inf
    truth = np.array([1.0, 2.0, inf, inf, 3.0])
    estimate = np.array([1.2, 3.0, inf, 2.0, 3.4])  # near, far, both clear, one clear, near with 5 % of 3 m
    assert scan_agreement(truth, estimate) == pytest.approx(3 / 5)
    with pytest.raises(ValueError, match="same beams"):
        scan_agreement(truth, estimate[:3])
