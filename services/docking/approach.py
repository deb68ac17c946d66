"""Approach geometry derived from a dock pose: staging poses, line waypoints, the control target.

A dock pose is the robot's base_link pose when docked (contacts mated); the dock's plate stands ahead
of it. Everything here is expressed along the dock's *heading* ``(cos yaw, sin yaw)`` and its *left
normal* ``(-sin yaw, cos yaw)``, so one set of offsets works for any dock in any room.

Two approaches are described:

- the line approach (stage beside the approach line, turn onto it, stop in front, drive straight in):
  :func:`line_approach`; for the dock at ``(-1.0, 0.83, -pi/2)`` its default offsets give the staging
  goal ``(0.0, 2.0, 0)``, waypoints ``(-1.0, 2.0)`` and ``(-1.0, 1.4)`` and the dock itself;
- the graceful approach (stage straight behind the dock facing it, then one smooth curve in):
  :func:`graceful_staging_pose` and :func:`docking_target`, after Nav2's opennav_docking staging pose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from shared.geometry import Pose2D, wrap_angle


@dataclass(frozen=True, slots=True)
class LineApproachOffsets:
    """Where the line approach's poses sit relative to the dock (metres back along its heading)."""

    #: The first waypoint, where the robot joins the approach line.
    line_waypoint_back_m: float = 1.17
    #: The waypoint in front of the dock, from which the robot drives straight in.
    front_waypoint_back_m: float = 0.57
    #: The staging goal sits this far from the line waypoint along the dock's left normal.
    staging_left_m: float = 1.0
    #: Staging yaw relative to the dock's yaw.
    staging_yaw_offset_rad: float = math.pi / 2


DEFAULT_LINE_OFFSETS = LineApproachOffsets()

#: How far behind the dock the graceful approach stages. Measured with ``services.docking.bench`` over
#: starts +-0.15 m / +-0.3 rad around it: 0.7 m gives the shortest median time to contact (closer starts
#: need a wider manoeuvre) and sub-millimetre median lateral error; Nav2's default is also 0.7 m.
GRACEFUL_STAGING_OFFSET_M = 0.7


@dataclass(frozen=True, slots=True)
class LineApproach:
    """The line approach's poses in the map frame."""

    staging_goal: Pose2D
    line_waypoint: Pose2D
    front_waypoint: Pose2D
    dock: Pose2D

    @property
    def goals(self) -> tuple[Pose2D, Pose2D, Pose2D]:
        """The line controller's goals after staging, in order."""
        return (self.line_waypoint, self.front_waypoint, self.dock)


@dataclass(frozen=True, slots=True)
class DockFrameError:
    """A robot pose seen from the dock: how far it still is from the docked pose.

    ``along_m`` is negative while the robot is behind the dock pose (approaching), ``lateral_m`` is
    positive to the dock's left, ``yaw_rad`` is robot yaw minus dock yaw, wrapped.
    """

    along_m: float
    lateral_m: float
    yaw_rad: float


def dock_heading(dock_pose: Pose2D) -> tuple[float, float]:
    """Unit vector the docked robot faces (towards the plate)."""
    return (math.cos(dock_pose.yaw), math.sin(dock_pose.yaw))


def dock_left_normal(dock_pose: Pose2D) -> tuple[float, float]:
    """Unit vector to the docked robot's left."""
    return (-math.sin(dock_pose.yaw), math.cos(dock_pose.yaw))


def offset_along(
    dock_pose: Pose2D, ahead_m: float, left_m: float = 0.0, yaw_offset_rad: float = 0.0
) -> Pose2D:
    """The pose ``ahead_m`` along the dock's heading and ``left_m`` along its left normal."""
    hx, hy = dock_heading(dock_pose)
    lx, ly = dock_left_normal(dock_pose)
    return Pose2D(
        dock_pose.x + ahead_m * hx + left_m * lx,
        dock_pose.y + ahead_m * hy + left_m * ly,
        wrap_angle(dock_pose.yaw + yaw_offset_rad),
    )


def line_approach(dock_pose: Pose2D, offsets: LineApproachOffsets = DEFAULT_LINE_OFFSETS) -> LineApproach:
    """Staging goal and waypoints of the line approach for ``dock_pose``."""
    line_waypoint = offset_along(dock_pose, -offsets.line_waypoint_back_m)
    front_waypoint = offset_along(dock_pose, -offsets.front_waypoint_back_m)
    staging_goal = offset_along(
        dock_pose,
        -offsets.line_waypoint_back_m,
        offsets.staging_left_m,
        offsets.staging_yaw_offset_rad,
    )
    dock = Pose2D(dock_pose.x, dock_pose.y, wrap_angle(dock_pose.yaw))
    return LineApproach(staging_goal, line_waypoint, front_waypoint, dock)


def graceful_staging_pose(dock_pose: Pose2D, staging_offset_m: float = GRACEFUL_STAGING_OFFSET_M) -> Pose2D:
    """Straight behind the dock, facing it: where navigation hands over to the docking controller."""
    return offset_along(dock_pose, -staging_offset_m)


def docking_target(dock_pose: Pose2D, dock_target_past_m: float) -> Pose2D:
    """The control law's target: the dock pose pushed ``dock_target_past_m`` ahead, into the plate.

    Aiming past the plate keeps the target out of reach, so the law never has to settle (and never
    spirals around) a point the robot can reach; contact or charging ends the approach instead.
    """
    return offset_along(dock_pose, dock_target_past_m)


def dock_frame_error(robot_pose: Pose2D, dock_pose: Pose2D) -> DockFrameError:
    """The robot pose in the dock frame: along-axis, lateral and yaw error."""
    rel = robot_pose.relative_to(dock_pose)
    return DockFrameError(rel.x, rel.y, wrap_angle(robot_pose.yaw - dock_pose.yaw))


def within_contact_reach(robot_pose: Pose2D, dock_pose: Pose2D, contact_reach_m: float) -> bool:
    """True once the robot is at most ``contact_reach_m`` short of the dock pose along its axis."""
    return dock_frame_error(robot_pose, dock_pose).along_m >= -contact_reach_m
