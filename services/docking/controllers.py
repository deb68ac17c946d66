"""The docking controllers bound to their names: what each of :data:`shared.controllers.CONTROLLERS` does.

:mod:`shared.controllers` says what a controller is (its name, description, control period, where trials
start it); an entry here says what it builds: the approach law it steers with, whether it perceives the
dock while it drives, and the task that docks with it. The service's parameters, its node and its
executive ask the entry (``params.docking_controller``), never the name, so a new controller is one entry
here and one line of the shared table.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from services.docking.approach_control import (
    ApproachController,
    GracefulApproach,
    SeedApproach,
    graceful_params_with_speed,
)
from services.docking.dock_db import DockDatabase
from services.docking.dock_tracker import DockTracker
from services.docking.docking_run import DockingRun, DockRequest
from services.docking.errors import DockingError
from services.docking.ir_run import IrDockingRun
from services.docking.pose_filter import PoseFilterParams
from services.docking.task_io import Task
from shared.controllers import CONTROLLERS, ControllerInfo
from shared.geometry import Pose2D

if TYPE_CHECKING:
    from services.docking.params import Params


@dataclass(frozen=True)
class DockingController:
    """One controller: its public description and the parts the service builds from it."""

    info: ControllerInfo
    #: The approach law, from the service's parameters (also what the staging poses are computed with).
    approach: Callable[[Params], ApproachController]
    #: Waits for detections at staging, keeps the dock estimate across phases and takes over from
    #: navigation near the staging pose (the graceful approach); the line approach does none of these.
    perceives_while_driving: bool
    #: The task one docking request runs, given the latest map pose (``None`` before the first).
    docking_run: Callable[[Params, DockRequest, DockDatabase, Pose2D | None], Task]


def _graceful_approach(params: Params) -> ApproachController:
    law = graceful_params_with_speed(params.max_approach_speed_mps)
    law = replace(
        law,
        command_delay_s=params.command_delay_s,
        last_command_hold_s=params.base_cmd_vel_timeout_s or None,
    )
    if law.pose_estimator is not None:
        # The pose comes carried by odometry, smooth and fresh: trust it, only compensate its age.
        estimator = replace(law.pose_estimator, correction_gain=params.pose_correction_gain)
        law = replace(law, pose_estimator=estimator)
    return GracefulApproach(law, params.staging_offset_m)


def _line_approach(params: Params) -> ApproachController:
    return SeedApproach()


def _run_on_the_map(
    params: Params, request: DockRequest, database: DockDatabase, pose: Pose2D | None
) -> Task:
    """Staging by navigation, then the approach law on the map pose refined by detections."""
    tracker = DockTracker(
        replace(PoseFilterParams(), coef=params.detection_filter_coef), params.max_detection_offset_m
    )
    return DockingRun(request, database, params.approach_controller(), params.docking_config(), tracker)


def _run_on_the_beacon(
    params: Params, request: DockRequest, database: DockDatabase, pose: Pose2D | None
) -> Task:
    """Infrared docking: the database's dock, when it has one, only to stage in front of it."""
    try:
        dock = (
            request.dock_pose
            or database.choose(request.dock_id or None, pose, request.dock_type or None).pose2d
        )
    except DockingError:
        dock = None  # no such dock in the database: infrared docking needs none
    return IrDockingRun(
        max_time_s=min(params.max_docking_time_s, params.approach_timeout_s + 60.0),
        dock_pose=dock,
        staging_offset_m=params.staging_offset_m,
        max_staging_time_s=request.max_staging_time_s,
    )


REGISTRY: dict[str, DockingController] = {
    "graceful": DockingController(
        CONTROLLERS["graceful"], _graceful_approach, perceives_while_driving=True, docking_run=_run_on_the_map
    ),
    "seed": DockingController(
        CONTROLLERS["seed"], _line_approach, perceives_while_driving=False, docking_run=_run_on_the_map
    ),
    # Infrared docking stages where the line approach would (its staging poses serve the traffic rule).
    "ir": DockingController(
        CONTROLLERS["ir"], _line_approach, perceives_while_driving=False, docking_run=_run_on_the_beacon
    ),
}
