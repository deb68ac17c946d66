"""What the docking service knows at one moment: the snapshot the node hands its executive, and a sighting.

Pure (no bus, no clock): the executive and its policies import these without loading Zenoh;
:mod:`services.docking.inputs` fills them from what the node hears.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from services.docking.safety import LidarReturns, ObstacleParams, lidar_blocked, sonar_blocked
from services.docking.task_io import NavOutcome
from services.docking.traffic import Peer, PlanPoints
from shared.geometry import Pose2D
from shared.messages import BatteryState

#: A sensor reading older than this is ignored by the obstacle checks.
SENSOR_MAX_AGE_S = 0.5
CHARGING_STATUSES = (BatteryState.POWER_SUPPLY_STATUS_CHARGING, BatteryState.POWER_SUPPLY_STATUS_FULL)


@dataclass(frozen=True, slots=True)
class NavHeard:
    """The planner's goal as the navigation client knows it (the executive knows which request it was)."""

    busy: bool = False
    #: How the last goal ended (None while one runs).
    outcome: NavOutcome | None = None
    reason: str = ""


@dataclass(frozen=True, slots=True)
class Heard:
    """Everything the docking service knows at one moment of the node's clock, fresh readings only."""

    now_s: float
    #: The clock went back since the last tick (a reset): the pose history was forgotten.
    clock_reset: bool = False
    #: The robot's latest map pose, however old (to choose docks and measure distances).
    latest_pose: Pose2D | None = None
    #: The latest map pose while localisation is fresh, and how old it is (for the controllers).
    robot_pose: Pose2D | None = None
    pose_age_s: float = 0.0
    base_twist: tuple[float, float] | None = None
    #: The last battery_status's charge (0..1, as sent); None before the first.
    battery: float | None = None
    #: battery_status says CHARGING or FULL, and is fresh.
    charging: bool = False
    #: The lidar's latest scan, when fresh (its points in base_link are worked out when asked for).
    scan: LidarReturns | None = None
    #: The sonar's range, when fresh.
    sonar_range_m: float | None = None
    ir_dock: tuple[int, int, int] | None = None
    #: The localiser's map -> odom correction.
    map_to_odom: Pose2D | None = None
    nav: NavHeard = NavHeard()
    #: The fleet's other robots heard from lately (empty without the traffic rule).
    peers: tuple[Peer, ...] = ()
    #: This robot's own plan as its planner last published it (with the traffic rule; see ``Peer.plan``).
    own_plan: PlanPoints = None
    #: For debug logs: how old localisation and odometry are (s; inf: never heard).
    localisation_age_s: float = math.inf
    odometry_age_s: float = math.inf

    @property
    def scan_points(self) -> np.ndarray | None:
        """The lidar's returns in base_link (n x 2), when fresh."""
        return None if self.scan is None else self.scan.points

    def blocked(
        self, dock_in_base: Pose2D | None, obstacles: ObstacleParams, use_lidar: bool, use_sonar: bool
    ) -> tuple[bool, bool]:
        """Whether something that is not the dock (``dock_in_base``) is in the way ahead and behind."""
        ahead = behind = False
        if use_lidar and self.scan_points is not None:
            ahead = lidar_blocked(self.scan_points, True, dock_in_base, obstacles)
            # Reversing never goes towards the dock: nothing behind is excused.
            behind = lidar_blocked(self.scan_points, False, None, obstacles)
        if use_sonar and self.sonar_range_m is not None:
            ahead = ahead or sonar_blocked(self.sonar_range_m, dock_in_base, obstacles)
        return ahead, behind


@dataclass(frozen=True, slots=True)
class DockSighting:
    """A detection of the dock: its pose in base_link at ``stamp_s``, and the robot's map pose then."""

    dock_in_base: Pose2D
    robot_at_stamp: Pose2D
    stamp_s: float
