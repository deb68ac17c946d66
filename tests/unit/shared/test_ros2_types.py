"""zendock messages as ROS 2 Jazzy CDR: the bytes rosbags writes for the same message, and back."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from services.ros2_bridge.actions import ACTIONS
from shared.geometry import Pose2D
from shared.interface_types import (
    UUID,
    CancelGoalRequest,
    CancelGoalResponse,
    GoalInfo,
    GoalStatus,
    GoalStatusArray,
)
from shared.interfaces.behaviors import (
    ASSISTED_TELEOP,
    BACK_UP,
    DRIVE_ON_HEADING,
    SPIN,
    WAIT,
    AssistedTeleopFeedback,
    AssistedTeleopResult,
    BackUpFeedback,
    BackUpGoal,
    DriveOnHeadingFeedback,
    DriveOnHeadingResult,
    SpinFeedback,
    SpinGoal,
    SpinResult,
    WaitFeedback,
    WaitGoal,
)
from shared.interfaces.costmap import (
    ClearCostmapAroundPoseRequest,
    ClearCostmapAroundPoseResponse,
    ClearCostmapAroundRobotRequest,
    ClearCostmapAroundRobotResponse,
    ClearCostmapExceptRegionRequest,
    ClearCostmapExceptRegionResponse,
    Costmap,
    CostmapMetaData,
    GetCostmapRequest,
    GetCostmapResponse,
)
from shared.interfaces.docking import (
    DOCK_ROBOT,
    UNDOCK_ROBOT,
    DockRobotFeedback,
    DockRobotGoal,
    DockRobotResult,
    UndockRobotFeedback,
    UndockRobotGoal,
)
from shared.interfaces.lifecycle import (
    ACTIVE,
    ChangeStateRequest,
    ChangeStateResponse,
    GetStateRequest,
    GetStateResponse,
    ManageLifecycleNodesRequest,
    ManageLifecycleNodesResponse,
    Transition,
)
from shared.interfaces.navigation import (
    COMPUTE_PATH_THROUGH_POSES,
    COMPUTE_PATH_TO_POSE,
    FOLLOW_GPS_WAYPOINTS,
    FOLLOW_PATH,
    FOLLOW_WAYPOINTS,
    NAVIGATE_THROUGH_POSES,
    NAVIGATE_TO_POSE,
    SMOOTH_PATH,
    ClearEntireCostmapRequest,
    ClearEntireCostmapResponse,
    ComputePathThroughPosesFeedback,
    ComputePathThroughPosesGoal,
    ComputePathThroughPosesResult,
    ComputePathToPoseFeedback,
    ComputePathToPoseGoal,
    ComputePathToPoseResult,
    FollowGPSWaypointsFeedback,
    FollowGPSWaypointsGoal,
    FollowGPSWaypointsResult,
    FollowPathFeedback,
    FollowPathGoal,
    FollowPathResult,
    FollowWaypointsFeedback,
    FollowWaypointsGoal,
    FollowWaypointsResult,
    GeoPoint,
    GeoPose,
    LoadMapRequest,
    LoadMapResponse,
    MissedWaypoint,
    NavigateThroughPosesFeedback,
    NavigateThroughPosesGoal,
    NavigateThroughPosesResult,
    NavigateToPoseFeedback,
    NavigateToPoseGoal,
    NavigateToPoseResult,
    SmoothPathFeedback,
    SmoothPathGoal,
    SmoothPathResult,
)
from shared.messages import (
    BatteryState,
    CameraInfo,
    Clock,
    Duration,
    Float64MultiArray,
    Header,
    Image,
    LaserScan,
    MapMetaData,
    MultiArrayDimension,
    MultiArrayLayout,
    OccupancyGrid,
    Odometry,
    Path,
    Point,
    Pose,
    PoseStamped,
    PoseWithCovariance,
    PoseWithCovarianceStamped,
    Quaternion,
    Range,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
    Twist,
    TwistWithCovariance,
    Vector3,
)
from shared.ros2 import types
from shared.ros2.bridge_routes import INBOUND, OUTBOUND, SERVICES
from shared.schema import Message

HEADER = Header(Time(12, 345_000_000), "base_link")
POSE = Pose(Point(1.5, -2.25, 0.0), Quaternion(0.0, 0.0, math.sin(0.3), math.cos(0.3)))

EXAMPLES: dict[str, Message] = {
    "rosgraph_msgs/msg/Clock": Clock(Time(99, 5)),
    "tf2_msgs/msg/TFMessage": TFMessage(
        [
            TransformStamped(
                HEADER, "odom", Transform(Vector3(0.1, 0.2, 0.0), Quaternion(0.0, 0.0, 0.6, 0.8))
            ),
            TransformStamped(Header(Time(1, 2), "map"), "base_link", Transform(Vector3(-3.0, 4.0, 0.5))),
        ]
    ),
    "nav_msgs/msg/Odometry": Odometry(
        HEADER,
        "base_link",
        PoseWithCovariance(POSE, np.arange(36.0)),
        TwistWithCovariance(Twist.planar(0.3, -0.7), np.full(36, 0.01)),
    ),
    "geometry_msgs/msg/PoseWithCovarianceStamped": PoseWithCovarianceStamped(
        HEADER, PoseWithCovariance(POSE, np.arange(36.0))
    ),
    "lifecycle_msgs/srv/GetState_Request": GetStateRequest(),
    "lifecycle_msgs/srv/ChangeState_Request": ChangeStateRequest(Transition(id=4, label="deactivate")),
    "lifecycle_msgs/srv/ChangeState_Response": ChangeStateResponse(success=True),
    "nav2_msgs/srv/ManageLifecycleNodes_Request": ManageLifecycleNodesRequest(command=1),
    "nav2_msgs/srv/ClearCostmapExceptRegion_Request": ClearCostmapExceptRegionRequest(reset_distance=1.5),
    "nav2_msgs/srv/ClearCostmapExceptRegion_Response": ClearCostmapExceptRegionResponse(),
    "nav2_msgs/srv/ClearCostmapAroundRobot_Request": ClearCostmapAroundRobotRequest(reset_distance=0.5),
    "nav2_msgs/srv/ClearCostmapAroundRobot_Response": ClearCostmapAroundRobotResponse(),
    "nav2_msgs/srv/ClearCostmapAroundPose_Request": ClearCostmapAroundPoseRequest(
        PoseStamped(Header(Time(3, 0), "map"), Pose.from_pose2d(Pose2D(1.0, 2.0, 0.5))), 0.75
    ),
    "nav2_msgs/srv/ClearCostmapAroundPose_Response": ClearCostmapAroundPoseResponse(),
    "nav2_msgs/srv/ManageLifecycleNodes_Response": ManageLifecycleNodesResponse(success=True),
    "nav2_msgs/srv/GetCostmap_Request": GetCostmapRequest(),
    "nav2_msgs/srv/GetCostmap_Response": GetCostmapResponse(
        Costmap(
            HEADER,
            CostmapMetaData(Time(1, 2), Time(3, 4), "global_costmap", 0.05, 3, 2, POSE),
            np.array([0, 10, 253, 254, 255, 1], dtype=np.uint8),
        )
    ),
    "nav2_msgs/srv/ClearEntireCostmap_Request": ClearEntireCostmapRequest(),
    "nav2_msgs/srv/ClearEntireCostmap_Response": ClearEntireCostmapResponse(),
    "nav2_msgs/srv/LoadMap_Request": LoadMapRequest("/maps/room.yaml"),
    "nav2_msgs/srv/LoadMap_Response": LoadMapResponse(result=LoadMapResponse.RESULT_MAP_DOES_NOT_EXIST),
    "lifecycle_msgs/srv/GetState_Response": GetStateResponse(ACTIVE),
    "sensor_msgs/msg/LaserScan": LaserScan(
        HEADER,
        -3.1,
        3.1,
        0.0175,
        0.0001,
        0.1,
        0.12,
        12.0,
        np.array([1.0, math.inf, 0.5, -math.inf], dtype=np.float32),
        np.array([10.0, 0.0, 3.0, 1.0], dtype=np.float32),
    ),
    "sensor_msgs/msg/Range": Range(HEADER, Range.ULTRASOUND, 0.26, 0.02, 4.0, 1.234),
    "sensor_msgs/msg/Image": Image(HEADER, 2, 3, "rgb8", 0, 9, np.arange(18, dtype=np.uint8)),
    "sensor_msgs/msg/CameraInfo": CameraInfo(
        HEADER,
        480,
        640,
        "plumb_bob",
        np.zeros(5),
        np.array([500.0, 0, 320, 0, 500, 240, 0, 0, 1]),
        np.eye(3).ravel(),
        np.arange(12.0),
    ),
    "sensor_msgs/msg/BatteryState": BatteryState(
        HEADER,
        voltage=12.4,
        current=-0.4,
        charge=1.8,
        capacity=2.0,
        design_capacity=2.0,
        percentage=0.9,
        power_supply_status=2,
        power_supply_health=1,
        power_supply_technology=2,
        cell_voltage=np.array([4.1, 4.2, 4.1], dtype=np.float32),
        location="base_link",
        serial_number="zd-1",
    ),
    "std_msgs/msg/Float64MultiArray": Float64MultiArray(
        MultiArrayLayout([MultiArrayDimension("pose", 3, 3)], 0), np.array([1.0, 2.0, 0.5])
    ),
    "nav_msgs/msg/OccupancyGrid": OccupancyGrid(
        HEADER, MapMetaData(Time(3, 0), 0.05, 3, 2, POSE), np.array([0, 100, -1, 0, 0, 100], dtype=np.int8)
    ),
    "nav_msgs/msg/Path": Path(
        Header(Time(5, 0), "map"), [PoseStamped(HEADER, POSE), PoseStamped(HEADER, Pose())]
    ),
    "geometry_msgs/msg/PoseStamped": PoseStamped(Header(Time(7, 0), "map"), POSE),
    "geometry_msgs/msg/Twist": Twist(Vector3(0.25, 0.0, 0.0), Vector3(0.0, 0.0, -0.5)),
}

GOAL_ID = UUID(np.arange(16, dtype=np.uint8))
GOAL_INFO = GoalInfo(GOAL_ID, Time(4, 5))
#: The actions' parts: zendock's messages of the same names as rosidl's.
ACTION_EXAMPLES: dict[str, Message] = {
    "action_msgs/msg/GoalStatusArray": GoalStatusArray(
        [GoalStatus(GOAL_INFO, 2), GoalStatus(GoalInfo(UUID(), Time()), 4)]
    ),
    "action_msgs/srv/CancelGoal_Request": CancelGoalRequest(GOAL_INFO),
    "action_msgs/srv/CancelGoal_Response": CancelGoalResponse(0, [GOAL_INFO]),
    "nav2_msgs/action/DockRobot_SendGoal_Request": DOCK_ROBOT.send_goal_request(
        goal_id=GOAL_ID, goal=DockRobotGoal(True, "home", PoseStamped(HEADER, POSE), "charger", 120.0, False)
    ),
    "nav2_msgs/action/DockRobot_SendGoal_Response": DOCK_ROBOT.send_goal_response(
        accepted=True, stamp=Time(8, 9)
    ),
    "nav2_msgs/action/DockRobot_GetResult_Request": DOCK_ROBOT.get_result_request(goal_id=GOAL_ID),
    "nav2_msgs/action/DockRobot_GetResult_Response": DOCK_ROBOT.get_result_response(
        status=4, result=DockRobotResult(True, 0, 2)
    ),
    "nav2_msgs/action/DockRobot_FeedbackMessage": DOCK_ROBOT.feedback_message(
        goal_id=GOAL_ID, feedback=DockRobotFeedback(3, Duration(7, 100), 1)
    ),
    "nav2_msgs/action/UndockRobot_SendGoal_Request": UNDOCK_ROBOT.send_goal_request(
        goal_id=GOAL_ID, goal=UndockRobotGoal("charger", 15.0)
    ),
    "nav2_msgs/action/UndockRobot_FeedbackMessage": UNDOCK_ROBOT.feedback_message(
        goal_id=GOAL_ID, feedback=UndockRobotFeedback()
    ),
    "nav2_msgs/action/NavigateToPose_SendGoal_Request": NAVIGATE_TO_POSE.send_goal_request(
        goal_id=GOAL_ID, goal=NavigateToPoseGoal(PoseStamped(HEADER, POSE), "")
    ),
    "nav2_msgs/action/NavigateToPose_GetResult_Response": NAVIGATE_TO_POSE.get_result_response(
        status=6, result=NavigateToPoseResult(9002, "no valid path")
    ),
    "nav2_msgs/action/NavigateToPose_FeedbackMessage": NAVIGATE_TO_POSE.feedback_message(
        goal_id=GOAL_ID,
        feedback=NavigateToPoseFeedback(PoseStamped(HEADER, POSE), Duration(3, 0), Duration(9, 0), 1, 2.5),
    ),
    "nav2_msgs/action/ComputePathToPose_SendGoal_Request": COMPUTE_PATH_TO_POSE.send_goal_request(
        goal_id=GOAL_ID,
        goal=ComputePathToPoseGoal(PoseStamped(HEADER, POSE), PoseStamped(), "GridBased", False),
    ),
    "nav2_msgs/action/ComputePathToPose_GetResult_Response": COMPUTE_PATH_TO_POSE.get_result_response(
        status=4,
        result=ComputePathToPoseResult(
            Path(HEADER, [PoseStamped(HEADER, POSE)] * 3), Duration(0, 4_000_000), 0, ""
        ),
    ),
    "nav2_msgs/action/ComputePathToPose_FeedbackMessage": COMPUTE_PATH_TO_POSE.feedback_message(
        goal_id=GOAL_ID, feedback=ComputePathToPoseFeedback()
    ),
    "nav2_msgs/action/ComputePathThroughPoses_SendGoal_Request": COMPUTE_PATH_THROUGH_POSES.send_goal_request(
        goal_id=GOAL_ID,
        goal=ComputePathThroughPosesGoal([PoseStamped(HEADER, POSE)] * 2, PoseStamped(), "", True),
    ),
    "nav2_msgs/action/ComputePathThroughPoses_GetResult_Response": COMPUTE_PATH_THROUGH_POSES.get_result_response(
        status=6, result=ComputePathThroughPosesResult(Path(), Duration(), 308, "no path")
    ),
    "nav2_msgs/action/ComputePathThroughPoses_FeedbackMessage": COMPUTE_PATH_THROUGH_POSES.feedback_message(
        goal_id=GOAL_ID, feedback=ComputePathThroughPosesFeedback()
    ),
    "nav2_msgs/action/NavigateThroughPoses_SendGoal_Request": NAVIGATE_THROUGH_POSES.send_goal_request(
        goal_id=GOAL_ID, goal=NavigateThroughPosesGoal([PoseStamped(HEADER, POSE)] * 2, "")
    ),
    "nav2_msgs/action/NavigateThroughPoses_GetResult_Response": NAVIGATE_THROUGH_POSES.get_result_response(
        status=6, result=NavigateThroughPosesResult(9002, "pose 2: no valid path")
    ),
    "nav2_msgs/action/NavigateThroughPoses_FeedbackMessage": NAVIGATE_THROUGH_POSES.feedback_message(
        goal_id=GOAL_ID,
        feedback=NavigateThroughPosesFeedback(
            PoseStamped(HEADER, POSE), Duration(3, 0), Duration(9, 0), 1, 2.5, 2
        ),
    ),
    "nav2_msgs/action/FollowWaypoints_SendGoal_Request": FOLLOW_WAYPOINTS.send_goal_request(
        goal_id=GOAL_ID, goal=FollowWaypointsGoal(1, 0, [PoseStamped(HEADER, POSE)] * 3)
    ),
    "nav2_msgs/action/FollowWaypoints_GetResult_Response": FOLLOW_WAYPOINTS.get_result_response(
        status=4, result=FollowWaypointsResult([MissedWaypoint(1, PoseStamped(HEADER, POSE), 9001)], 0, "")
    ),
    "nav2_msgs/action/FollowWaypoints_FeedbackMessage": FOLLOW_WAYPOINTS.feedback_message(
        goal_id=GOAL_ID, feedback=FollowWaypointsFeedback(2)
    ),
    "nav2_msgs/action/FollowPath_SendGoal_Request": FOLLOW_PATH.send_goal_request(
        goal_id=GOAL_ID,
        goal=FollowPathGoal(Path(HEADER, [PoseStamped(HEADER, POSE)] * 2), "FollowPath", "", ""),
    ),
    "nav2_msgs/action/FollowPath_GetResult_Response": FOLLOW_PATH.get_result_response(
        status=6, result=FollowPathResult(106, "an obstacle on the path")
    ),
    "nav2_msgs/action/FollowPath_FeedbackMessage": FOLLOW_PATH.feedback_message(
        goal_id=GOAL_ID, feedback=FollowPathFeedback(1.25, 0.3)
    ),
    "nav2_msgs/action/FollowGPSWaypoints_SendGoal_Request": FOLLOW_GPS_WAYPOINTS.send_goal_request(
        goal_id=GOAL_ID,
        goal=FollowGPSWaypointsGoal(
            0, 0, [GeoPose(GeoPoint(48.1, 11.5, math.nan), Quaternion(0.0, 0.0, 0.0, 1.0))]
        ),
    ),
    "nav2_msgs/action/FollowGPSWaypoints_GetResult_Response": FOLLOW_GPS_WAYPOINTS.get_result_response(
        status=6, result=FollowGPSWaypointsResult([], 600, "no GPS")
    ),
    "nav2_msgs/action/FollowGPSWaypoints_FeedbackMessage": FOLLOW_GPS_WAYPOINTS.feedback_message(
        goal_id=GOAL_ID, feedback=FollowGPSWaypointsFeedback(0)
    ),
    "nav2_msgs/action/SmoothPath_SendGoal_Request": SMOOTH_PATH.send_goal_request(
        goal_id=GOAL_ID,
        goal=SmoothPathGoal(Path(HEADER, [PoseStamped(HEADER, POSE)] * 2), "", Duration(1, 0), True),
    ),
    "nav2_msgs/action/SmoothPath_GetResult_Response": SMOOTH_PATH.get_result_response(
        status=4,
        result=SmoothPathResult(Path(HEADER, [PoseStamped(HEADER, POSE)]), Duration(0, 1000), True, 0, ""),
    ),
    "nav2_msgs/action/SmoothPath_FeedbackMessage": SMOOTH_PATH.feedback_message(
        goal_id=GOAL_ID, feedback=SmoothPathFeedback()
    ),
    "nav2_msgs/action/AssistedTeleop_GetResult_Response": ASSISTED_TELEOP.get_result_response(
        status=6, result=AssistedTeleopResult(Duration(), 730, "not served")
    ),
    "nav2_msgs/action/AssistedTeleop_FeedbackMessage": ASSISTED_TELEOP.feedback_message(
        goal_id=GOAL_ID, feedback=AssistedTeleopFeedback(Duration(2, 0))
    ),
    "nav2_msgs/action/Spin_SendGoal_Request": SPIN.send_goal_request(
        goal_id=GOAL_ID, goal=SpinGoal(1.57, Duration(10, 0))
    ),
    "nav2_msgs/action/Spin_GetResult_Response": SPIN.get_result_response(
        status=6, result=SpinResult(Duration(1, 500), 703, "an obstacle")
    ),
    "nav2_msgs/action/Spin_FeedbackMessage": SPIN.feedback_message(
        goal_id=GOAL_ID, feedback=SpinFeedback(0.75)
    ),
    "nav2_msgs/action/BackUp_SendGoal_Request": BACK_UP.send_goal_request(
        goal_id=GOAL_ID, goal=BackUpGoal(Point(0.15, 0.0, 0.0), 0.025, Duration(10, 0))
    ),
    "nav2_msgs/action/BackUp_FeedbackMessage": BACK_UP.feedback_message(
        goal_id=GOAL_ID, feedback=BackUpFeedback(0.05)
    ),
    "nav2_msgs/action/DriveOnHeading_GetResult_Response": DRIVE_ON_HEADING.get_result_response(
        status=4, result=DriveOnHeadingResult(Duration(6, 0), 0, "")
    ),
    "nav2_msgs/action/DriveOnHeading_FeedbackMessage": DRIVE_ON_HEADING.feedback_message(
        goal_id=GOAL_ID, feedback=DriveOnHeadingFeedback(0.1)
    ),
    "nav2_msgs/action/Wait_SendGoal_Request": WAIT.send_goal_request(
        goal_id=GOAL_ID, goal=WaitGoal(Duration(2, 0))
    ),
    "nav2_msgs/action/Wait_FeedbackMessage": WAIT.feedback_message(
        goal_id=GOAL_ID, feedback=WaitFeedback(Duration(1, 250_000_000))
    ),
}
EXAMPLES.update(ACTION_EXAMPLES)


def _independent(value: Any, ros_type: str) -> Any:
    """The rosbags message built from zendock's msgpack map, field by field, without the converter."""
    store = types.typestore()
    cls = store.types[ros_type]
    _, fields = store.fielddefs[ros_type]
    wire = value.to_dict() if isinstance(value, Message) else value
    values: dict[str, Any] = {}
    for name, (kind, detail) in fields:
        given = wire.get(name) if wire is not None else None
        if kind == 2:
            values[name] = _independent(given, detail)
        elif kind == 1:
            values[name] = given if given is not None else ("" if detail[0] == "string" else 0)
        else:
            sub_kind, sub_detail = detail[0]
            if sub_kind == 2:
                values[name] = [_independent(item, sub_detail) for item in (given or [])]
            else:
                dtype = {"float32": np.float32, "float64": np.float64, "uint8": np.uint8, "int8": np.int8}[
                    sub_detail[0]
                ]
                raw = (
                    np.frombuffer(given, dtype=dtype)
                    if isinstance(given, bytes)
                    else np.array(given or [], dtype=dtype)
                )
                values[name] = raw if kind == 4 or raw.size else np.zeros(detail[1], dtype=dtype)
    return cls(**values)


def test_every_bridged_type_has_an_example() -> None:
    """Every topic's type, and both sides of each of an action's services (DockRobot's; the others differ
    only in goal, result and feedback, which have examples of their own)."""
    dock = next(a for a in ACTIONS if a.name == "dock_robot")
    services = {f"{s.ros_type}_{side}" for s in dock.services for side in ("Request", "Response")}
    services |= {f"{s.ros_type}_{side}" for s in SERVICES for side in ("Request", "Response")}
    assert {r.ros_type for r in OUTBOUND} | {"geometry_msgs/msg/Twist"} | services <= set(EXAMPLES)


@pytest.mark.parametrize("ros_type", sorted(EXAMPLES))
def test_cdr_bytes_equal_rosbags_for_the_same_message(ros_type: str) -> None:
    msg = EXAMPLES[ros_type]
    ours = types.to_cdr(msg, ros_type)
    theirs = bytes(types.typestore().serialize_cdr(_independent(msg, ros_type), ros_type))
    assert ours[:4] == b"\x00\x01\x00\x00"  # CDR, little endian
    assert ours == theirs


@pytest.mark.parametrize("ros_type", sorted(EXAMPLES))
def test_cdr_reads_back_into_the_same_zendock_message(ros_type: str) -> None:
    msg = EXAMPLES[ros_type]
    back = types.from_ros(types.from_cdr(types.to_cdr(msg, ros_type), ros_type), type(msg))
    assert back.encode() == _float32_rounded(msg, ros_type).encode()  # bytes: NaN equals NaN


def _float32_rounded(msg: Message, ros_type: str) -> Message:
    """ROS 2 carries some fields as float32 (BatteryState, Range, LaserScan): compare what survives."""
    return types.from_ros(
        types.typestore().deserialize_cdr(
            types.typestore().serialize_cdr(_independent(msg, ros_type), ros_type), ros_type
        ),
        type(msg),
    )


def test_type_hashes_are_jazzys_published_values() -> None:
    assert types.type_hash("std_msgs/msg/String") == (
        "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
    )
    assert types.type_hash("geometry_msgs/msg/Twist") == (
        "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a"
    )
    for route in (*OUTBOUND, *INBOUND):
        assert (
            types.type_hash(route.ros_type).startswith("RIHS01_")
            and len(types.type_hash(route.ros_type)) == 71
        )


def test_char_is_uint8_in_every_types_hash() -> None:
    """ROS 2's IDL maps ``char`` to ``uint8``, so rosidl describes (and hashes) it as one; rosbags keeps
    ``char``. The expected value is ``type_hashes`` in ``share/std_msgs/msg/Char.json`` of Jazzy's std_msgs 5.3.6
    as packaged on PyPI (``ros-jazzy-std-msgs`` 5.3.6 requires ``ros-std-msgs==5.3.6``, built from the ROS
    sources by ros-python-wheels); its ``char__description.c`` has the same bytes. rmw_zenoh puts this hash
    in every key and token (rmw_publisher_data.cpp, ``rosidl_stringify_type_hash``), so a wrong one means no
    match with a ROS 2 peer."""
    assert types.type_hash("std_msgs/msg/Char") == (
        "RIHS01_3ad2d04dd29ba19d04b16659afa3ccaedd691914b02a64e82e252f2fa6a586a9"
    )
    assert types.typestore().fielddefs["std_msgs/msg/Char"][1] == [("data", (1, ("uint8", 0)))]
    for name, (_consts, fields) in types.typestore().fielddefs.items():
        assert "'char'" not in repr(fields), name


def test_service_hashes_describe_request_response_and_event() -> None:
    """A service's hash is its description type's (request, response, event), not its request's: checked
    against the published hash of example_interfaces/srv/AddTwoInts, built by the same rule."""
    from rosbags.typesys import Stores, get_typestore

    from shared.ros2.interfaces import service_definitions

    store = get_typestore(Stores.EMPTY)
    store.register(dict(types.typestore().fielddefs))
    store.register(service_definitions("example_interfaces/srv/AddTwoInts", "int64 a\nint64 b", "int64 sum"))
    assert store.hash_rihs01("example_interfaces/srv/AddTwoInts") == (
        "RIHS01_e118de6bf5eeb66a2491b5bda11202e7b68f198d6f67922cf30364858239c81a"
    )
    for action in ACTIONS:
        for service in action.services:
            assert types.type_hash(service.ros_type) != types.type_hash(f"{service.ros_type}_Request")


def test_lifecycle_get_state_hash_is_jazzys() -> None:
    """The value is ``type_hashes`` in ``share/lifecycle_msgs/srv/GetState.json`` of Jazzy's lifecycle_msgs
    2.0.3 as packaged on PyPI: Nav2 scripts' ``amcl/get_state`` must match it on rmw_zenoh's keys."""
    assert types.type_hash("lifecycle_msgs/srv/GetState") == (
        "RIHS01_800a0a5aae599782b02932de0caf563f6dc4e7e94b794eadde075ba2cbef9795"
    )


def test_lifecycle_change_state_hash_is_jazzys() -> None:
    """``type_hashes`` in ``share/lifecycle_msgs/srv/ChangeState.json`` of Jazzy's lifecycle_msgs 2.0.3 (PyPI):
    what Nav2's lifecycle managers and ``ros2 lifecycle set`` ask on rmw_zenoh's keys."""
    assert types.type_hash("lifecycle_msgs/srv/ChangeState") == (
        "RIHS01_356fe34f0475a43acf54542013af4167b0e729f77ea22ffb045c6ad8e20668e5"
    )


def test_parameter_service_hashes_are_jazzys() -> None:
    """``type_hashes`` in ``share/rcl_interfaces/srv/*.json`` of Jazzy's rcl_interfaces (PyPI): what
    ``ros2 param`` asks on rmw_zenoh's keys."""
    expected = {
        "ListParameters": "3e6062bfbb27bfb8730d4cef2558221f51a11646d78e7bb30a1e83afac3aad9d",
        "GetParameters": "bf9803d5c74cf989a5de3e0c2e99444599a627c7ff75f97b8c05b01003675cbc",
        "SetParameters": "56eed9a67e169f9cb6c1f987bc88f868c14a8fc9f743a263bc734c154015d7e0",
        "SetParametersAtomically": "0e192ef259c07fc3c07a13191d27002222e65e00ccec653ca05e856f79285fcd",
        "DescribeParameters": "845b484d71eb0673dae682f2e3ba3c4851a65a3dcfb97bddd82c5b57e91e4cff",
        "GetParameterTypes": "da199c878688b3e530bdfe3ca8f74cb9fa0c303101e980a9e8f260e25e1c80ca",
    }
    for name, digest in expected.items():
        assert types.type_hash(f"rcl_interfaces/srv/{name}") == f"RIHS01_{digest}", name


def test_nav2_costmap_and_map_service_hashes_are_rosidls() -> None:
    """The values are ``type_hashes`` in ``share/nav2_msgs/srv/*.json`` and ``msg/Costmap.json`` as rosidl
    generates them (``make ros2``) from the same Jazzy definitions (Nav2 jazzy f4108e5b)."""
    assert types.type_hash("nav2_msgs/srv/GetCostmap") == (
        "RIHS01_1c3d7c36488ea60fb6ddf76482faf36cee004e29433fea60b8cee011fcd8ad73"
    )
    assert types.type_hash("nav2_msgs/srv/ClearEntireCostmap") == (
        "RIHS01_553f54f9cadab44553fdf5627433fcb6701f71c1fc2eb55a7b4a004fdeeab952"
    )
    assert types.type_hash("nav2_msgs/srv/LoadMap") == (
        "RIHS01_eb875de5ea9bb394573effc3f239015b19869dd7a8988136768372c6ef907ec1"
    )
    assert types.type_hash("nav2_msgs/srv/ManageLifecycleNodes") == (
        "RIHS01_1850f4f677251bb8f7744e3c0a87ef4f66c205e2f8740a8330251af7d1804460"
    )
    assert types.type_hash("nav2_msgs/srv/ClearCostmapAroundPose") == (
        "RIHS01_cd006590d0a7b5a357138518c1ac6f733782a0317f5d8fc92f46158e5438138c"
    )
    assert types.type_hash("nav2_msgs/srv/ClearCostmapAroundRobot") == (
        "RIHS01_24973b6e8b3e7ec70c37d6b411f1e32cef44051dfe7f34ad0ee7d6d9055cd6ea"
    )
    assert types.type_hash("nav2_msgs/srv/ClearCostmapExceptRegion") == (
        "RIHS01_66032323269ef923ab356273a7b7fc1c5acd9ccd46cd14bdcd265642a4012b05"
    )
    assert types.type_hash("nav2_msgs/msg/Costmap") == (
        "RIHS01_d51bf7aecafdbb3f8f98215de648abe6d53f8db69156d6e143125d2ad2bf0027"
    )


def test_zendock_docking_types_have_jazzy_names() -> None:
    assert (
        types.jazzy_name(DOCK_ROBOT.feedback_message.TYPE_NAME)
        == "nav2_msgs/action/DockRobot_FeedbackMessage"
    )
    assert (
        types.zendock_name("nav2_msgs/action/DockRobot_FeedbackMessage")
        == DOCK_ROBOT.feedback_message.TYPE_NAME
    )
    assert (
        types.jazzy_name("sensor_msgs/msg/Range")
        == types.zendock_name("sensor_msgs/msg/Range")
        == "sensor_msgs/msg/Range"
    )
    assert types.knows(types.jazzy_name(UNDOCK_ROBOT.feedback_message.TYPE_NAME))


def test_unknown_types_and_bad_bytes_are_named() -> None:
    with pytest.raises(types.Ros2TypeError, match="not a ROS 2 Jazzy message type"):
        types.type_hash("zendock_msgs/msg/Nothing")
    good = types.to_cdr(EXAMPLES["sensor_msgs/msg/BatteryState"], "sensor_msgs/msg/BatteryState")
    with pytest.raises(types.Ros2TypeError, match="not CDR"):
        types.from_cdr(b"\x93\x01garbage", "geometry_msgs/msg/Twist")
    with pytest.raises(types.Ros2TypeError, match="malformed CDR"):
        types.from_cdr(good[:30], "sensor_msgs/msg/BatteryState")
    with pytest.raises(types.Ros2TypeError, match="malformed CDR"):
        types.from_cdr(b"\x00\x01\x00\x00\xff\xff\xff\x7f", "nav_msgs/msg/Path")
