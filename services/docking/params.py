"""The docking service's parameters: one validated set, mapped onto the runs' and controllers' settings.

Which controller runs decides several settings at once (the graceful approach waits for a detection,
keeps perceiving while it drives, and takes over from navigation near the staging pose; the line
approach does none of these): that choice is made here once, not tested again at each use.
"""

from __future__ import annotations

from typing import Annotated

import msgspec
from msgspec import Meta

from services.docking.approach import GRACEFUL_STAGING_OFFSET_M
from services.docking.approach_control import ApproachController, back_off_gains
from services.docking.controllers import REGISTRY, DockingController
from services.docking.dock_db import load_dock_db
from services.docking.docking_run import DockingConfig
from services.docking.undocking_run import UndockConfig
from shared.controllers import CONTROLLERS, DEFAULT_CONTROLLER, ControllerName, choices_help
from shared.parameters import ServiceParams, runtime_settable
from shared.structs import blaming

#: When a runtime change of a docking parameter takes effect: each run is built from the parameters.
NEXT_RUN = "at the next docking or undocking run"


class Params(ServiceParams):
    """Parameters of ``python -m services.docking`` (``-p name=value`` or a YAML file)."""

    dock_database: Annotated[
        str,
        Meta(
            description="dock database YAML (docks: [{id, pose: [x, y, yaw], type}]); a world file is accepted as is"
        ),
    ]
    controller: Annotated[
        ControllerName, Meta(description="final approach controller: " + choices_help(CONTROLLERS))
    ] = DEFAULT_CONTROLLER
    dock_id: Annotated[str, Meta(description="dock for the battery trigger ('' : the nearest)")] = ""
    auto_dock: Annotated[
        bool,
        Meta(
            description="dock when the battery crosses below low_battery_threshold (off: a program of "
            "the user's own docks, and this service does not react to the same low battery)",
            extra=runtime_settable("at once"),
        ),
    ] = True
    low_battery_threshold: Annotated[float, Meta(gt=0.0, le=1.0)] = 0.25
    resume_at: Annotated[
        float, Meta(gt=0.0, le=1.0, description="charge at which a patrol resumes (undocking)")
    ] = 0.95
    patrol: Annotated[
        list[tuple[float, float, float]],
        Meta(
            description="patrol waypoints [x, y, yaw] (empty: "
            "those a fleet world in dock_database gives this robot)"
        ),
    ] = msgspec.field(default_factory=list)
    max_retries: Annotated[int, Meta(ge=0, extra=runtime_settable(NEXT_RUN))] = 3
    use_detection: Annotated[bool, Meta(description="refine the dock pose from detected_dock_pose")] = True
    allow_blind_docking: Annotated[
        bool, Meta(description="dock on the database pose when no detection comes")
    ] = True
    min_detections: Annotated[int, Meta(ge=1)] = 3
    initial_perception_timeout_s: Annotated[float, Meta(gt=0.0)] = 2.0
    detection_filter_coef: Annotated[float, Meta(gt=0.0, le=1.0)] = 0.1
    max_detection_offset_m: Annotated[
        float, Meta(gt=0.0, description="detections farther from the database pose are ignored")
    ] = 0.5
    max_staging_time_s: Annotated[
        float, Meta(gt=0.0, description="staging time limit of battery-triggered runs")
    ] = 120.0
    approach_timeout_s: Annotated[float, Meta(gt=0.0, extra=runtime_settable(NEXT_RUN))] = 120.0
    obstacle_timeout_s: Annotated[
        float, Meta(gt=0.0, description="held by an obstacle this long, the attempt fails")
    ] = 20.0
    wait_charge_timeout_s: Annotated[float, Meta(gt=0.0)] = 5.0
    max_docking_time_s: Annotated[float, Meta(gt=0.0)] = 600.0
    staging_offset_m: Annotated[float, Meta(gt=0.2)] = GRACEFUL_STAGING_OFFSET_M
    handover_distance_m: Annotated[
        float,
        Meta(
            ge=0.0,
            description="graceful: the approach takes over from navigation this close to the staging "
            "pose, with the dock in view (0: navigation always stops at the staging pose first)",
            extra=runtime_settable(NEXT_RUN),
        ),
    ] = 0.45
    max_approach_speed_mps: Annotated[
        float,
        Meta(gt=0.0, le=0.5, description="graceful approach top speed", extra=runtime_settable(NEXT_RUN)),
    ] = 0.5
    undock_speed_mps: Annotated[
        float, Meta(gt=0.0, le=0.5, description="backing off the dock, m/s", extra=runtime_settable(NEXT_RUN))
    ] = 0.2
    max_pose_age_s: Annotated[float, Meta(gt=0.0, description="older localisation is stale: hold still")] = (
        0.5
    )
    max_localisation_age_s: Annotated[
        float,
        Meta(
            gt=0.0,
            description="... unless odometry no older than max_pose_age_s carries a pose this old forward",
        ),
    ] = 2.0
    pose_latency_s: Annotated[
        float, Meta(ge=0.0, description="how old map_to_base_link_pose2d is when it arrives")
    ] = 0.01
    max_control_pose_age_s: Annotated[
        float,
        Meta(gt=0.0, description="graceful: an older pose holds the approach still (the tick came late)"),
    ] = 0.25
    #: The simulated base answers a command within a physics step or two of its arrival, and the pose the
    #: approach steers from is already brought up to its tick, so little is left to predict: a longer dead
    #: time makes the robot believe itself ahead of where it is, brake early and steer off the axis. 0.05 s
    #: leaves room for the bus's latency at higher speed-ups (the sweep: docs/measurements, measurement 78).
    command_delay_s: Annotated[
        float,
        Meta(
            ge=0.0,
            le=1.0,
            description="graceful: dead time from cmd_vel to the base's response, predicted "
            "through with the commands still on their way",
            extra=runtime_settable(NEXT_RUN),
        ),
    ] = 0.05
    base_cmd_vel_timeout_s: Annotated[
        float,
        Meta(
            ge=0.0,
            le=2.0,
            description="graceful: how long the base drives on its last command before its cmd_vel "
            "watchdog stops it; near the plate the approach only sends commands that would still meet it "
            "gently if they were the last (0: count on the next command)",
            extra=runtime_settable(NEXT_RUN),
        ),
    ] = 0.3
    pose_correction_gain: Annotated[
        float,
        Meta(
            gt=0.0,
            le=1.0,
            description="graceful: how far each pose moves the approach's pose estimate "
            "(1: the odometry-carried pose as it is, compensated for its age)",
            extra=runtime_settable(NEXT_RUN),
        ),
    ] = 1.0
    battery_timeout_s: Annotated[
        float, Meta(gt=0.0, description="older battery_status counts as not charging")
    ] = 2.0
    obstacle_stop_distance_m: Annotated[float, Meta(ge=0.0)] = 0.3
    use_lidar: bool = True
    use_sonar: bool = True
    feedback_period_s: Annotated[float, Meta(gt=0.0)] = 0.5
    fleet: Annotated[
        bool,
        Meta(
            description="robots share docks: ask the fleet service (fleet/reserve_dock, one "
            "namespace up) for a dock before driving to one, and release it after undocking"
        ),
    ] = False
    fleet_patience_s: Annotated[
        float,
        Meta(
            gt=0.0, description="fleet: no answer for this long, the fleet is down: dock at a dock seen free"
        ),
    ] = 5.0

    def __post_init__(self) -> None:
        with blaming("dock_database"):
            load_dock_db(self.dock_database)  # a ConfigError names the file and the entry
        if self.resume_at <= self.low_battery_threshold:
            raise ValueError(
                f"resume_at: {self.resume_at} must be above low_battery_threshold "
                f"({self.low_battery_threshold})"
            )

    @property
    def docking_controller(self) -> DockingController:
        """The controller these parameters name: what it builds and how it docks."""
        return REGISTRY[self.controller]

    def approach_controller(self) -> ApproachController:
        """A fresh final-approach controller as these parameters configure it."""
        return self.docking_controller.approach(self)

    def docking_config(self) -> DockingConfig:
        """The docking run's settings."""
        graceful = self.docking_controller.perceives_while_driving
        return DockingConfig(
            max_retries=self.max_retries,
            use_detection=self.use_detection,
            allow_blind_docking=self.allow_blind_docking,
            wait_for_detection=graceful,
            continuous_perception=graceful,
            max_control_pose_age_s=self.max_control_pose_age_s if graceful else None,
            handover_distance_m=self.handover_distance_m
            if graceful and self.handover_distance_m > 0
            else None,
            min_detections=self.min_detections,
            initial_perception_timeout_s=self.initial_perception_timeout_s,
            approach_timeout_s=self.approach_timeout_s,
            obstacle_timeout_s=self.obstacle_timeout_s,
            wait_charge_timeout_s=self.wait_charge_timeout_s,
            max_docking_time_s=self.max_docking_time_s,
            staging_offset_m=self.staging_offset_m,
            back_off_gains=back_off_gains(self.undock_speed_mps),
        )

    def undock_config(self) -> UndockConfig:
        """The undocking run's settings."""
        return UndockConfig(
            staging_offset_m=self.staging_offset_m, gains=back_off_gains(self.undock_speed_mps)
        )
