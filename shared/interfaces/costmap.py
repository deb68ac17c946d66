"""``nav2_msgs/srv/GetCostmap`` and the costmap services under Nav2's names, for Nav2 scripts.

Nav2 keeps two costmaps, each behind its own node: ``global_costmap`` (the whole map) and
``local_costmap`` (a window round the robot). zendock's planner keeps one layered costmap (the map, the
lidar, the glass the sonar heard, inflated) and answers for both: ``global_costmap/get_costmap`` is the
whole of it, ``local_costmap/get_costmap`` the square of ``local_costmap_size_m`` centred on the robot.
Costs are Nav2's (``nav2_costmap_2d``): 0 free, 253 inscribed (the robot's centre there collides), 254
lethal, 255 unknown, and in between the inflation's decay.
"""

from __future__ import annotations

from dataclasses import field
from typing import Any, ClassVar

import numpy as np

from shared.interface_types import Empty, ServiceType
from shared.messages import Header, Pose, PoseStamped, Time
from shared.schema import Message, UInt8Array, UInt32, message


@message("nav2_msgs/msg/CostmapMetaData")
class CostmapMetaData(Message):
    map_load_time: Time = field(default_factory=Time)
    update_time: Time = field(default_factory=Time)
    layer: str = ""
    resolution: float = 0.0
    size_x: UInt32 = 0
    size_y: UInt32 = 0
    origin: Pose = field(default_factory=Pose)


@message("nav2_msgs/msg/Costmap")
class Costmap(Message):
    """Row-major costs from the origin cell (0, 0), ``size_x`` to a row."""

    FREE_SPACE: ClassVar[int] = 0
    INSCRIBED_INFLATED_OBSTACLE: ClassVar[int] = 253
    LETHAL_OBSTACLE: ClassVar[int] = 254
    NO_INFORMATION: ClassVar[int] = 255

    header: Header = field(default_factory=Header)
    metadata: CostmapMetaData = field(default_factory=CostmapMetaData)
    data: UInt8Array = field(default_factory=lambda: np.zeros(0, dtype=np.uint8))


@message("nav2_msgs/srv/GetCostmap_Request")
class GetCostmapRequest(Message):
    """``specs`` is Nav2's, and ignored there too: the costmap comes as it is."""

    specs: CostmapMetaData = field(default_factory=CostmapMetaData)


@message("nav2_msgs/srv/GetCostmap_Response")
class GetCostmapResponse(Message):
    map: Costmap = field(default_factory=Costmap)


GET_COSTMAP = ServiceType("nav2_msgs/srv/GetCostmap", GetCostmapRequest, GetCostmapResponse)

#: Nav2's service names (relative to the namespace), which the planner answers.
GLOBAL_COSTMAP_GET = "global_costmap/get_costmap"
LOCAL_COSTMAP_GET = "local_costmap/get_costmap"
GLOBAL_COSTMAP_CLEAR = "global_costmap/clear_entirely_global_costmap"
LOCAL_COSTMAP_CLEAR = "local_costmap/clear_entirely_local_costmap"


@message("nav2_msgs/srv/ClearCostmapExceptRegion_Request")
class ClearCostmapExceptRegionRequest(Message):
    """Clear all but the square of side ``reset_distance`` (m) centred on the robot."""

    reset_distance: float = 0.0


@message("nav2_msgs/srv/ClearCostmapExceptRegion_Response")
class ClearCostmapExceptRegionResponse(Message):
    response: Empty = field(default_factory=Empty)


@message("nav2_msgs/srv/ClearCostmapAroundRobot_Request")
class ClearCostmapAroundRobotRequest(Message):
    """Clear the square of side ``reset_distance`` (m) centred on the robot."""

    reset_distance: float = 0.0


@message("nav2_msgs/srv/ClearCostmapAroundRobot_Response")
class ClearCostmapAroundRobotResponse(Message):
    response: Empty = field(default_factory=Empty)


@message("nav2_msgs/srv/ClearCostmapAroundPose_Request")
class ClearCostmapAroundPoseRequest(Message):
    """Clear the square of side ``reset_distance`` (m) centred on ``pose`` (in ``map``)."""

    pose: PoseStamped = field(default_factory=PoseStamped)
    reset_distance: float = 0.0


@message("nav2_msgs/srv/ClearCostmapAroundPose_Response")
class ClearCostmapAroundPoseResponse(Message):
    response: Empty = field(default_factory=Empty)


CLEAR_COSTMAP_EXCEPT_REGION = ServiceType(
    "nav2_msgs/srv/ClearCostmapExceptRegion",
    ClearCostmapExceptRegionRequest,
    ClearCostmapExceptRegionResponse,
)
CLEAR_COSTMAP_AROUND_ROBOT = ServiceType(
    "nav2_msgs/srv/ClearCostmapAroundRobot", ClearCostmapAroundRobotRequest, ClearCostmapAroundRobotResponse
)
CLEAR_COSTMAP_AROUND_POSE = ServiceType(
    "nav2_msgs/srv/ClearCostmapAroundPose", ClearCostmapAroundPoseRequest, ClearCostmapAroundPoseResponse
)


def region_clear_service(costmap: str, what: str) -> str:
    """``("local", "around_robot")`` -> ``local_costmap/clear_costmap_around_robot`` (Nav2's names)."""
    return f"{costmap}_costmap/clear_costmap_{what}"


#: Nav2's region clears, each on both costmaps: (what, type).
REGION_CLEARS: tuple[tuple[str, ServiceType[Any, Any]], ...] = (
    ("except_region", CLEAR_COSTMAP_EXCEPT_REGION),
    ("around_robot", CLEAR_COSTMAP_AROUND_ROBOT),
    ("around_pose", CLEAR_COSTMAP_AROUND_POSE),
)
