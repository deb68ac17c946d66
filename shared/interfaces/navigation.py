"""The navigation stack's interfaces, mirroring nav2_msgs: NavigateToPose, ClearEntireCostmap, LoadMap."""

from __future__ import annotations

import enum
from dataclasses import field
from typing import Annotated, ClassVar

from shared.interface_types import ActionType, Empty, ServiceType
from shared.messages import Duration, OccupancyGrid, PoseStamped
from shared.schema import Message, Range, UInt16, message


@message("nav2_msgs/action/NavigateToPose_Goal")
class NavigateToPoseGoal(Message):
    pose: PoseStamped = field(default_factory=PoseStamped)
    behavior_tree: str = ""


class NavigateErrorCode(enum.IntEnum):
    """Why navigation failed (nav2's planner/controller code ranges, kept small)."""

    NONE = 0
    UNKNOWN = 9000
    INVALID_GOAL = 9001
    NO_VALID_PATH = 9002
    GOAL_OCCUPIED = 9003
    START_OCCUPIED = 9004
    TIMEOUT = 9005
    STUCK = 9006
    NO_POSE = 9007
    NO_MAP = 9008
    PREEMPTED = 9009
    CANCELED = 9010


@message("nav2_msgs/action/NavigateToPose_Result")
class NavigateToPoseResult(Message):
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/NavigateToPose_Feedback")
class NavigateToPoseFeedback(Message):
    current_pose: PoseStamped = field(default_factory=PoseStamped)
    navigation_time: Duration = field(default_factory=Duration)
    estimated_time_remaining: Duration = field(default_factory=Duration)
    number_of_recoveries: Annotated[int, Range(-(2**15), 2**15 - 1)] = 0
    distance_remaining: float = 0.0


NAVIGATE_TO_POSE = ActionType(
    "nav2_msgs/action/NavigateToPose", NavigateToPoseGoal, NavigateToPoseResult, NavigateToPoseFeedback
)


@message("nav2_msgs/srv/ClearEntireCostmap_Request")
class ClearEntireCostmapRequest(Message):
    request: Empty = field(default_factory=Empty)


@message("nav2_msgs/srv/ClearEntireCostmap_Response")
class ClearEntireCostmapResponse(Message):
    response: Empty = field(default_factory=Empty)


CLEAR_ENTIRE_COSTMAP = ServiceType(
    "nav2_msgs/srv/ClearEntireCostmap", ClearEntireCostmapRequest, ClearEntireCostmapResponse
)


@message("nav2_msgs/srv/LoadMap_Request")
class LoadMapRequest(Message):
    map_url: str = ""


@message("nav2_msgs/srv/LoadMap_Response")
class LoadMapResponse(Message):
    RESULT_SUCCESS: ClassVar[int] = 0
    RESULT_MAP_DOES_NOT_EXIST: ClassVar[int] = 1
    RESULT_INVALID_MAP_DATA: ClassVar[int] = 2
    RESULT_INVALID_MAP_METADATA: ClassVar[int] = 3
    RESULT_UNDEFINED_FAILURE: ClassVar[int] = 255
    map: OccupancyGrid = field(default_factory=OccupancyGrid)
    result: Annotated[int, Range(0, 255)] = 0


LOAD_MAP = ServiceType("nav2_msgs/srv/LoadMap", LoadMapRequest, LoadMapResponse)

# Service names (relative to the namespace), as the navigation stack names them.
CLEAR_COSTMAPS_SERVICE = "planner/clear_entirely_costmaps"
LOAD_MAP_SERVICE = "map_server/load_map"
