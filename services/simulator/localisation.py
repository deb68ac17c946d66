"""The simulated localiser: the map -> odom transform a localisation node would publish.

REP-105 chains map -> odom -> base_link. Odometry supplies odom -> base_link; a localiser corrects its
drift by publishing map -> odom. The simulator plays a localiser that is exactly right, or off by a
fixed ``error`` expressed in base_link, so that

    map->odom * odom->base_link = true_pose * error

i.e. the robot believes it stands at ``true_pose * error``. An error of ``Pose2D(0.05, 0, 0)`` makes the
robot think it is 5 cm ahead of where it really is, whatever its heading; the docking controller must
then rely on the dock detection, which the error does not affect.
"""

from __future__ import annotations

import numpy as np

from shared.geometry import Pose2D

#: A beam agrees when the ranges from the truth and from an estimate differ by at most this (plus 5 % of
#: the range): a localiser's scan matcher pulls a pose this far off back in.
AGREEMENT_TOLERANCE_M = 0.3
AGREEMENT_TOLERANCE_FRACTION = 0.05


def believed_pose(true_pose: Pose2D, error: Pose2D) -> Pose2D:
    """Where the robot believes it is in the map: ``true_pose * error``."""
    return true_pose.compose(error)


def map_to_odom(true_pose: Pose2D, odom_to_base: Pose2D, error: Pose2D | None = None) -> Pose2D:
    """The map -> odom transform that makes the published chain land on ``true_pose * error``.

    ``odom_to_base`` is the odometry pose (which may have drifted); the result absorbs that drift, as a
    localiser does, and adds the configured localisation ``error``.
    """
    belief = believed_pose(true_pose, error or Pose2D())
    return belief.compose(odom_to_base.inverse())


def scan_agreement(from_truth: np.ndarray, from_estimate: np.ndarray) -> float:
    """The fraction of lidar beams on which the map, ray-cast from an estimated pose (``from_estimate``),
    agrees with what the lidar sees from the true pose (``from_truth``): both see nothing in range
    (``inf``), or both a surface at about the same range: what a scan matcher would think of an initial
    pose (the figures for the shipped rooms are in docs/nav2-api.md)."""
    if from_truth.shape != from_estimate.shape or from_truth.size == 0:
        raise ValueError("two scans of the same beams are needed")
    both_clear = np.isinf(from_truth) & np.isinf(from_estimate)
    near = np.minimum(from_truth, from_estimate)
    with np.errstate(invalid="ignore"):
        close = (
            np.isfinite(from_truth)
            & np.isfinite(from_estimate)
            & (
                np.abs(from_truth - from_estimate)
                <= AGREEMENT_TOLERANCE_M + AGREEMENT_TOLERANCE_FRACTION * near
            )
        )
    return float(np.mean(both_clear | close))
