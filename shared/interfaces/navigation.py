"""The navigation stack's interfaces, mirroring nav2_msgs: NavigateToPose, NavigateThroughPoses,
FollowWaypoints, FollowPath, ComputePathToPose, ComputePathThroughPoses, SmoothPath, ClearEntireCostmap,
LoadMap."""

from __future__ import annotations

import enum
from dataclasses import field
from typing import Annotated, ClassVar

from shared.interface_types import ActionType, Empty, ServiceType
from shared.messages import Duration, OccupancyGrid, Path, PoseStamped, Quaternion
from shared.schema import FloatAny, Int16, Message, Range, UInt16, UInt32, message


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


@message("nav2_msgs/action/NavigateThroughPoses_Goal")
class NavigateThroughPosesGoal(Message):
    poses: list[PoseStamped] = field(default_factory=list)
    behavior_tree: str = ""


@message("nav2_msgs/action/NavigateThroughPoses_Result")
class NavigateThroughPosesResult(Message):
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/NavigateThroughPoses_Feedback")
class NavigateThroughPosesFeedback(Message):
    current_pose: PoseStamped = field(default_factory=PoseStamped)
    navigation_time: Duration = field(default_factory=Duration)
    estimated_time_remaining: Duration = field(default_factory=Duration)
    number_of_recoveries: Annotated[int, Range(-(2**15), 2**15 - 1)] = 0
    distance_remaining: float = 0.0
    number_of_poses_remaining: Annotated[int, Range(-(2**15), 2**15 - 1)] = 0


NAVIGATE_THROUGH_POSES = ActionType(
    "nav2_msgs/action/NavigateThroughPoses",
    NavigateThroughPosesGoal,
    NavigateThroughPosesResult,
    NavigateThroughPosesFeedback,
)


class FollowWaypointsErrorCode(enum.IntEnum):
    NONE = 0
    UNKNOWN = 600
    TASK_EXECUTOR_FAILED = 601


@message("nav2_msgs/msg/MissedWaypoint")
class MissedWaypoint(Message):
    index: UInt32 = 0
    goal: PoseStamped = field(default_factory=PoseStamped)
    error_code: UInt16 = 0


@message("nav2_msgs/action/FollowWaypoints_Goal")
class FollowWaypointsGoal(Message):
    #: How many times to go round again after the first pass (0: once).
    number_of_loops: UInt32 = 0
    #: The waypoint to start from.
    goal_index: UInt32 = 0
    poses: list[PoseStamped] = field(default_factory=list)


@message("nav2_msgs/action/FollowWaypoints_Result")
class FollowWaypointsResult(Message):
    missed_waypoints: list[MissedWaypoint] = field(default_factory=list)
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/FollowWaypoints_Feedback")
class FollowWaypointsFeedback(Message):
    current_waypoint: UInt32 = 0


FOLLOW_WAYPOINTS = ActionType(
    "nav2_msgs/action/FollowWaypoints", FollowWaypointsGoal, FollowWaypointsResult, FollowWaypointsFeedback
)


@message("geographic_msgs/msg/GeoPoint")
class GeoPoint(Message):
    latitude: float = 0.0
    longitude: float = 0.0
    #: NaN when unspecified, as geographic_msgs has it.
    altitude: FloatAny = 0.0


@message("geographic_msgs/msg/GeoPose")
class GeoPose(Message):
    position: GeoPoint = field(default_factory=GeoPoint)
    orientation: Quaternion = field(default_factory=Quaternion)


@message("nav2_msgs/action/FollowGPSWaypoints_Goal")
class FollowGPSWaypointsGoal(Message):
    number_of_loops: UInt32 = 0
    goal_index: UInt32 = 0
    gps_poses: list[GeoPose] = field(default_factory=list)


@message("nav2_msgs/action/FollowGPSWaypoints_Result")
class FollowGPSWaypointsResult(Message):
    missed_waypoints: list[MissedWaypoint] = field(default_factory=list)
    error_code: Int16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/FollowGPSWaypoints_Feedback")
class FollowGPSWaypointsFeedback(Message):
    current_waypoint: UInt32 = 0


FOLLOW_GPS_WAYPOINTS = ActionType(
    "nav2_msgs/action/FollowGPSWaypoints",
    FollowGPSWaypointsGoal,
    FollowGPSWaypointsResult,
    FollowGPSWaypointsFeedback,
)


class FollowPathErrorCode(enum.IntEnum):
    NONE = 0
    UNKNOWN = 100
    INVALID_CONTROLLER = 101
    TF_ERROR = 102
    INVALID_PATH = 103
    PATIENCE_EXCEEDED = 104
    FAILED_TO_MAKE_PROGRESS = 105
    NO_VALID_CONTROL = 106
    CONTROLLER_TIMED_OUT = 107


@message("nav2_msgs/action/FollowPath_Goal")
class FollowPathGoal(Message):
    path: Path = field(default_factory=Path)
    controller_id: str = ""
    goal_checker_id: str = ""
    progress_checker_id: str = ""


@message("nav2_msgs/action/FollowPath_Result")
class FollowPathResult(Message):
    # ROS 2's result also has ``std_msgs/Empty result``: nothing to carry, ROS 2's default is sent.
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/FollowPath_Feedback")
class FollowPathFeedback(Message):
    distance_to_goal: float = 0.0
    speed: float = 0.0


FOLLOW_PATH = ActionType("nav2_msgs/action/FollowPath", FollowPathGoal, FollowPathResult, FollowPathFeedback)


class ComputePathErrorCode(enum.IntEnum):
    """Why ``compute_path_to_pose`` found no path (Nav2's 200s); ``compute_path_through_poses`` uses the
    same reasons 100 higher (:func:`through_poses_code`), and 309 for no via-points at all."""

    NONE = 0
    UNKNOWN = 200
    INVALID_PLANNER = 201
    TF_ERROR = 202
    START_OUTSIDE_MAP = 203
    GOAL_OUTSIDE_MAP = 204
    START_OCCUPIED = 205
    GOAL_OCCUPIED = 206
    TIMEOUT = 207
    NO_VALID_PATH = 208


#: ComputePathThroughPoses' NO_VIAPOINTS_GIVEN: an empty list of goals.
NO_VIAPOINTS_GIVEN = 309


def through_poses_code(code: ComputePathErrorCode) -> int:
    """The ComputePathThroughPoses code for the same reason (300s): 0 stays 0."""
    return int(code) + 100 if code else 0


@message("nav2_msgs/action/ComputePathToPose_Goal")
class ComputePathToPoseGoal(Message):
    goal: PoseStamped = field(default_factory=PoseStamped)
    start: PoseStamped = field(default_factory=PoseStamped)
    planner_id: str = ""
    #: False: the path starts at the robot's pose; True: at ``start``.
    use_start: bool = False


@message("nav2_msgs/action/ComputePathToPose_Result")
class ComputePathToPoseResult(Message):
    path: Path = field(default_factory=Path)
    planning_time: Duration = field(default_factory=Duration)
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/ComputePathToPose_Feedback")
class ComputePathToPoseFeedback(Message):
    pass


COMPUTE_PATH_TO_POSE = ActionType(
    "nav2_msgs/action/ComputePathToPose",
    ComputePathToPoseGoal,
    ComputePathToPoseResult,
    ComputePathToPoseFeedback,
)


@message("nav2_msgs/action/ComputePathThroughPoses_Goal")
class ComputePathThroughPosesGoal(Message):
    goals: list[PoseStamped] = field(default_factory=list)
    start: PoseStamped = field(default_factory=PoseStamped)
    planner_id: str = ""
    use_start: bool = False


@message("nav2_msgs/action/ComputePathThroughPoses_Result")
class ComputePathThroughPosesResult(Message):
    path: Path = field(default_factory=Path)
    planning_time: Duration = field(default_factory=Duration)
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/ComputePathThroughPoses_Feedback")
class ComputePathThroughPosesFeedback(Message):
    pass


COMPUTE_PATH_THROUGH_POSES = ActionType(
    "nav2_msgs/action/ComputePathThroughPoses",
    ComputePathThroughPosesGoal,
    ComputePathThroughPosesResult,
    ComputePathThroughPosesFeedback,
)


class SmoothPathErrorCode(enum.IntEnum):
    NONE = 0
    UNKNOWN = 500
    INVALID_SMOOTHER = 501
    TIMEOUT = 502
    SMOOTHED_PATH_IN_COLLISION = 503
    FAILED_TO_SMOOTH_PATH = 504
    INVALID_PATH = 505


@message("nav2_msgs/action/SmoothPath_Goal")
class SmoothPathGoal(Message):
    path: Path = field(default_factory=Path)
    smoother_id: str = ""
    max_smoothing_duration: Duration = field(default_factory=Duration)
    check_for_collisions: bool = False


@message("nav2_msgs/action/SmoothPath_Result")
class SmoothPathResult(Message):
    path: Path = field(default_factory=Path)
    smoothing_duration: Duration = field(default_factory=Duration)
    was_completed: bool = False
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/SmoothPath_Feedback")
class SmoothPathFeedback(Message):
    pass


SMOOTH_PATH = ActionType("nav2_msgs/action/SmoothPath", SmoothPathGoal, SmoothPathResult, SmoothPathFeedback)


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
