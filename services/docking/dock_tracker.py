"""The dock pose refined from detections, in the map frame, for the dock a docking run is heading to.

Each detection is the dock pose in base_link at the camera's capture time. Composed with the robot's
map pose *at that time* (:class:`~shared.pose_tracking.PoseTrack`: odometry at the stamp
through the localiser's current correction) it becomes a dock pose in the map frame, which
:class:`~services.docking.pose_filter.DockPoseFilter` smooths. When the localiser's correction moves, the
estimate moves with it (:meth:`DockTracker.shift`), so in effect the dock is tracked in the odometry
frame, as Nav2's opennav_docking does in its fixed frame. If the localiser is off by a few centimetres
the filtered dock is off by the same amount, so the robot's pose relative to it -- all that the approach
needs -- stays right: the error cancels. Detections far from the database pose of the expected dock
belong to another dock (or are wrong) and are ignored.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from services.docking.pose_filter import DockPoseFilter, PoseFilterParams
from shared.geometry import Pose2D, wrap_angle


@dataclass(frozen=True, slots=True)
class DockEstimate:
    """The refined dock pose and how it was obtained."""

    pose: Pose2D
    #: Stamp of the newest detection that updated it.
    stamp_s: float
    #: Detections accepted since the tracker was last reset.
    detections: int


class DockTracker:
    """Filters detections of one expected dock into a map-frame pose; see the module docstring."""

    def __init__(
        self,
        filter_params: PoseFilterParams | None = None,
        max_offset_m: float = 0.5,
        max_yaw_offset_rad: float = 0.6,
    ) -> None:
        self._filter = DockPoseFilter(filter_params)
        self.max_offset_m = max_offset_m
        self.max_yaw_offset_rad = max_yaw_offset_rad
        self.expected: Pose2D | None = None
        self.detections = 0
        self.ignored = 0
        #: Detections stamped before this time are ignored (see :meth:`reset`).
        self.accept_from_s = -math.inf

    def expect(self, dock_pose: Pose2D | None) -> None:
        """Track the dock near ``dock_pose`` (its database pose); None stops tracking. A new dock resets."""
        if dock_pose != self.expected:
            self.expected = dock_pose
            self.reset()

    def reset(self, accept_from_s: float = -math.inf) -> None:
        """Forget the estimate; ignore detections taken before ``accept_from_s`` (the robot was moving)."""
        self._filter.reset()
        self.detections = 0
        self.accept_from_s = accept_from_s

    def add(self, dock_in_base: Pose2D, robot_pose_at_stamp: Pose2D, stamp_s: float) -> bool:
        """Feed one detection; True when it was accepted."""
        if self.expected is None or stamp_s < self.accept_from_s:
            return False
        measured = robot_pose_at_stamp.compose(dock_in_base)
        far = measured.distance_to(self.expected) > self.max_offset_m
        turned = abs(wrap_angle(measured.yaw - self.expected.yaw)) > self.max_yaw_offset_rad
        if far or turned:
            self.ignored += 1
            return False
        self._filter.update(measured, stamp_s)
        self.detections += 1
        return True

    def shift(self, correction: Pose2D) -> None:
        """The localiser moved its map -> odom correction by ``correction`` (new = correction * old): the
        detected dock moves with the robot's odometry, as Nav2 tracks it in the odom frame. The
        database pose it is checked against stays where the map has it."""
        self._filter.shift(correction)

    def estimate(self) -> DockEstimate | None:
        """The filtered dock pose, or None before the first accepted detection since the last reset."""
        pose = self._filter.pose
        if pose is None or self.detections == 0:
            return None
        return DockEstimate(pose, self._filter.stamp_s, self.detections)
