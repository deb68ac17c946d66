"""Whether the robot's charging contacts are mated with a dock, from the ground-truth pose.

The dock's contacts are spring-loaded: they reach ``contact_reach_m`` out of the plate, so they mate as
soon as the robot's base_link is within that distance short of the dock pose, provided the robot is
centred and square to the dock. This is the simulated "charging" signal a real dock reports.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, NamedTuple

import numpy as np
from msgspec import Meta

from shared.geometry import Pose2D, wrap_angle
from shared.models.component import ComponentParams
from shared.models.footprint import footprint_corners, polygon_distance
from shared.world import DOCK_GEOMETRY, Dock


class DockContactParams(ComponentParams, frozen=True):
    rate_hz: Annotated[float, Meta(gt=0, description="dock_contact messages per second (sim time)")] = 20.0
    contact_reach_m: Annotated[float, Meta(ge=0)] = 0.05
    #: How far past the dock pose base_link may be and still count (the body stops it anyway).
    overshoot_slack_m: Annotated[float, Meta(ge=0)] = 0.01
    max_lateral_error_m: Annotated[float, Meta(ge=0)] = 0.04
    max_yaw_error_rad: Annotated[float, Meta(ge=0)] = 0.1
    #: Footprint and dock body closer than this are touching.
    touch_tolerance_m: Annotated[float, Meta(ge=0)] = 0.005
    #: Docks farther than this from base_link are not reported.
    search_radius_m: Annotated[float, Meta(ge=0)] = 1.0


class DockContact(NamedTuple):
    """The nearest dock and how the robot stands against it, in the dock pose's frame.

    ``along_error_m`` is base_link's offset along the dock axis: negative while short of the dock pose.
    ``lateral_error_m`` is the sideways offset, ``yaw_error_rad`` the heading error (robot minus dock).
    With no dock within reach ``dock_id`` is None, nothing is mated or touching, and the errors are nan.
    """

    dock_id: str | None
    mated: bool
    touching: bool
    lateral_error_m: float
    yaw_error_rad: float
    along_error_m: float


NO_DOCK = DockContact(None, False, False, math.nan, math.nan, math.nan)


def dock_contact(robot_pose: Pose2D, docks: Sequence[Dock], params: DockContactParams) -> DockContact:
    """Contact state against the dock nearest to base_link (see :class:`DockContact`)."""
    if not docks:
        return NO_DOCK
    dock = min(docks, key=lambda d: robot_pose.distance_to(d.pose2d))
    if robot_pose.distance_to(dock.pose2d) > params.search_radius_m:
        return NO_DOCK
    offset = robot_pose.relative_to(dock.pose2d)
    along, lateral, yaw_error = offset.x, offset.y, wrap_angle(robot_pose.yaw - dock.pose2d.yaw)
    mated = (
        -params.contact_reach_m <= along <= params.overshoot_slack_m
        and abs(lateral) <= params.max_lateral_error_m
        and abs(yaw_error) <= params.max_yaw_error_rad
    )
    gap_m = polygon_distance(
        footprint_corners(robot_pose), np.asarray(DOCK_GEOMETRY.body_box(dock).corners())
    )
    return DockContact(dock.id, mated, gap_m <= params.touch_tolerance_m, lateral, yaw_error, along)
