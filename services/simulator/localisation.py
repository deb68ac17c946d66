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

from shared.geometry import Pose2D


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
