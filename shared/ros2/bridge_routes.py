"""What zendock's ROS 2 faces carry: each zendock key, its ROS 2 topic and type, who owns it, its QoS.

Both faces read these tables: ``services.ros2_bridge`` (rmw_zenoh's wire on zendock's router) and
``services.ros2_dds`` (real rclpy on the default middleware, Fast DDS). The owner is the zendock service
that publishes (or, for commands, consumes) the key; a face announces it to ROS 2 as a node of that name,
so ``ros2 node list`` shows zendock's services and ``ros2 topic info -v`` names the service behind each topic.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from shared import topics
from shared.action import action_key
from shared.interface_types import ActionType, GoalStatusArray, ServiceType
from shared.interfaces.behaviors import ASSISTED_TELEOP, BACK_UP, DRIVE_ON_HEADING, SPIN, WAIT
from shared.interfaces.costmap import (
    GET_COSTMAP,
    GLOBAL_COSTMAP_CLEAR,
    GLOBAL_COSTMAP_GET,
    LOCAL_COSTMAP_CLEAR,
    LOCAL_COSTMAP_GET,
    REGION_CLEARS,
    GetCostmapResponse,
    region_clear_service,
)
from shared.interfaces.docking import DOCK_ROBOT, UNDOCK_ROBOT
from shared.interfaces.lifecycle import (
    CHANGE_STATE,
    GET_STATE,
    MANAGE_LIFECYCLE_NODES,
    UNKNOWN,
    ChangeStateResponse,
    GetStateResponse,
    ManageLifecycleNodesResponse,
)
from shared.interfaces.navigation import (
    CLEAR_ENTIRE_COSTMAP,
    COMPUTE_PATH_THROUGH_POSES,
    COMPUTE_PATH_TO_POSE,
    FOLLOW_GPS_WAYPOINTS,
    FOLLOW_PATH,
    FOLLOW_WAYPOINTS,
    LOAD_MAP,
    LOAD_MAP_SERVICE,
    NAVIGATE_THROUGH_POSES,
    NAVIGATE_TO_POSE,
    SMOOTH_PATH,
    ClearEntireCostmapResponse,
    LoadMapResponse,
)
from shared.messages import (
    BatteryState,
    CameraInfo,
    Clock,
    Float64MultiArray,
    Image,
    LaserScan,
    OccupancyGrid,
    Odometry,
    Path,
    PoseStamped,
    PoseWithCovarianceStamped,
    Range,
    TFMessage,
    Twist,
)
from shared.nav2_stand_ins import (
    NAV2_LIFECYCLE_MANAGERS,
    NAV2_STAND_INS,
    change_state_service,
    get_state_service,
)
from shared.ros2 import interfaces
from shared.ros2.wire import LATCHED, RELIABLE, SENSOR_DATA, QosProfile
from shared.schema import Message


@dataclass(frozen=True)
class Route:
    """One zendock key on one ROS 2 topic (``ros_topic`` is relative to the bridge's ROS namespace)."""

    zendock_topic: str
    ros_topic: str
    zendock_type: type[Message]
    ros_type: str
    owner: str
    qos: QosProfile = RELIABLE

    @property
    def latched(self) -> bool:
        """Transient local in ROS 2: a subscriber that joins late gets the last message at once."""
        return self.qos == LATCHED


def _out(
    topic: str,
    zendock_type: type[Message],
    owner: str,
    qos: QosProfile = RELIABLE,
    ros_type: str | None = None,
) -> Route:
    return Route(topic, topic, zendock_type, ros_type or zendock_type.TYPE_NAME, owner, qos)


@dataclass(frozen=True)
class BridgedAction:
    """One of zendock's actions as a ROS 2 action: its name (relative, as the topics), Jazzy type, owner
    and zendock's action type (whose server the ROS 2 goals are relayed to)."""

    name: str
    ros_type: str
    owner: str
    zendock: ActionType[Any, Any, Any]


ACTIONS: tuple[BridgedAction, ...] = (
    BridgedAction(topics.DOCK_ROBOT, interfaces.DOCK_ROBOT, "docking", DOCK_ROBOT),
    BridgedAction(topics.UNDOCK_ROBOT, interfaces.UNDOCK_ROBOT, "docking", UNDOCK_ROBOT),
    BridgedAction(topics.NAVIGATE_TO_POSE, interfaces.NAVIGATE_TO_POSE, "planner", NAVIGATE_TO_POSE),
    BridgedAction(
        topics.NAVIGATE_THROUGH_POSES, interfaces.NAVIGATE_THROUGH_POSES, "planner", NAVIGATE_THROUGH_POSES
    ),
    BridgedAction(topics.FOLLOW_WAYPOINTS, interfaces.FOLLOW_WAYPOINTS, "planner", FOLLOW_WAYPOINTS),
    BridgedAction(
        topics.FOLLOW_GPS_WAYPOINTS, interfaces.FOLLOW_GPS_WAYPOINTS, "planner", FOLLOW_GPS_WAYPOINTS
    ),
    BridgedAction(
        topics.COMPUTE_PATH_TO_POSE, interfaces.COMPUTE_PATH_TO_POSE, "planner", COMPUTE_PATH_TO_POSE
    ),
    BridgedAction(
        topics.COMPUTE_PATH_THROUGH_POSES,
        interfaces.COMPUTE_PATH_THROUGH_POSES,
        "planner",
        COMPUTE_PATH_THROUGH_POSES,
    ),
    BridgedAction(topics.SMOOTH_PATH, interfaces.SMOOTH_PATH, "planner", SMOOTH_PATH),
    BridgedAction(topics.FOLLOW_PATH, interfaces.FOLLOW_PATH, "planner", FOLLOW_PATH),
    BridgedAction(topics.SPIN, interfaces.SPIN, "planner", SPIN),
    BridgedAction(topics.BACKUP, interfaces.BACK_UP, "planner", BACK_UP),
    BridgedAction(topics.DRIVE_ON_HEADING, interfaces.DRIVE_ON_HEADING, "planner", DRIVE_ON_HEADING),
    BridgedAction(topics.WAIT, interfaces.WAIT, "planner", WAIT),
    BridgedAction(topics.ASSISTED_TELEOP, interfaces.ASSISTED_TELEOP, "planner", ASSISTED_TELEOP),
)


@dataclass(frozen=True)
class BridgedService:
    """One of zendock's request/response services as a ROS 2 service: its name (relative), Jazzy type,
    owner and zendock's service type (the relayed request's and reply's)."""

    name: str
    ros_type: str
    owner: str
    zendock: ServiceType[Any, Any]
    #: The face's reply when zendock's service does not answer (None: an error reply). A ROS 2 client
    #: may wait for its reply without a timeout (Nav2 scripts do, for ``get_state``), and rmw_zenoh's
    #: drops error replies: such a client would wait forever.
    unanswered: Callable[[], Message] | None = None
    #: How long a face waits for zendock's answer (a map load reads a file and re-inflates the costmap).
    wait_s: float = 10.0


def _unknown_state() -> GetStateResponse:
    return GetStateResponse(current_state=UNKNOWN)


def _not_done() -> ChangeStateResponse:
    return ChangeStateResponse(success=False)


def _not_managed() -> ManageLifecycleNodesResponse:
    return ManageLifecycleNodesResponse(success=False)


def _map_not_loaded() -> LoadMapResponse:
    return LoadMapResponse(result=LoadMapResponse.RESULT_UNDEFINED_FAILURE)


#: Nav2's lifecycle queries and changes, answered by the zendock service standing in for each Nav2 node
#: (``unknown``, or ``success: false``, while it does not answer: a script asks again), and its lifecycle
#: managers' ``manage_nodes``; the planner's costmap and map services under Nav2's
#: names (an empty costmap, or a failed load, while it does not answer).
SERVICES: tuple[BridgedService, ...] = (
    *(
        BridgedService(get_state_service(nav2_node), interfaces.GET_STATE, owner, GET_STATE, _unknown_state)
        for nav2_node, owner in NAV2_STAND_INS.items()
    ),
    *(
        BridgedService(name, interfaces.GET_COSTMAP, "planner", GET_COSTMAP, GetCostmapResponse)
        for name in (GLOBAL_COSTMAP_GET, LOCAL_COSTMAP_GET)
    ),
    *(
        BridgedService(
            name, interfaces.CLEAR_ENTIRE_COSTMAP, "planner", CLEAR_ENTIRE_COSTMAP, ClearEntireCostmapResponse
        )
        for name in (GLOBAL_COSTMAP_CLEAR, LOCAL_COSTMAP_CLEAR)
    ),
    *(
        BridgedService(region_clear_service(costmap, what), srv.type_name, "planner", srv, srv.response)
        for costmap in ("global", "local")
        for what, srv in REGION_CLEARS
    ),
    BridgedService(LOAD_MAP_SERVICE, interfaces.LOAD_MAP, "planner", LOAD_MAP, _map_not_loaded, wait_s=30.0),
    *(
        BridgedService(
            change_state_service(nav2_node), interfaces.CHANGE_STATE, owner, CHANGE_STATE, _not_done
        )
        for nav2_node, owner in NAV2_STAND_INS.items()
    ),
    *(
        BridgedService(
            manager.manage_nodes,
            interfaces.MANAGE_LIFECYCLE_NODES,
            manager.host,
            MANAGE_LIFECYCLE_NODES,
            _not_managed,
            wait_s=30.0,
        )
        for manager in NAV2_LIFECYCLE_MANAGERS
    ),
)


def _action_topics(action: BridgedAction) -> tuple[Route, ...]:
    """An action's feedback and status topics (its services are relayed by each face on its own)."""
    parts = interfaces.action_parts(action.ros_type)
    return (
        _out(
            action_key(action.name, "feedback"),
            action.zendock.feedback_message,
            action.owner,
            ros_type=parts["feedback"],
        ),
        _out(
            action_key(action.name, "status"),
            GoalStatusArray,
            action.owner,
            LATCHED,
            ros_type=parts["status"],
        ),
    )


#: zendock -> ROS 2 topics of their own (not parts of an action), forwarded only while a ROS 2
#: subscription for the topic exists (transient-local ones always).
TOPICS: tuple[Route, ...] = (
    _out(topics.CLOCK, Clock, "simulator"),
    _out(topics.TF, TFMessage, "simulator"),
    _out(topics.TF_STATIC, TFMessage, "simulator", LATCHED),
    _out(topics.ODOM, Odometry, "simulator"),
    _out(topics.SCAN, LaserScan, "simulator", SENSOR_DATA),
    _out(topics.ULTRASONIC, Range, "simulator", SENSOR_DATA),
    _out(topics.CAMERA_IMAGE, Image, "simulator", SENSOR_DATA),
    _out(topics.CAMERA_INFO, CameraInfo, "simulator", SENSOR_DATA),
    _out(topics.BATTERY_STATUS, BatteryState, "battery"),
    _out(topics.POSE2D, Float64MultiArray, "pose"),
    _out(topics.AMCL_POSE, PoseWithCovarianceStamped, "pose", LATCHED),
    _out(topics.MAP, OccupancyGrid, "planner", LATCHED),
    _out(topics.PLAN, Path, "planner"),
    _out(topics.DETECTED_DOCK_POSE, PoseStamped, "perception", SENSOR_DATA),
)

#: Every zendock -> ROS 2 topic on rmw_zenoh's wire: the topics and the actions' feedback and status (an
#: rclpy ActionServer publishes those two itself).
OUTBOUND: tuple[Route, ...] = TOPICS + tuple(route for action in ACTIONS for route in _action_topics(action))

#: What a ROS 2 command on cmd_vel may be: Twist, or TwistStamped as Jazzy's controllers publish.
TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
#: RViz's "2D Goal Pose": navigate there.
GOAL_POSE = "goal_pose"
#: RViz's "2D Pose Estimate": where the localiser should believe the robot is.
INITIAL_POSE = "initialpose"


@dataclass(frozen=True)
class Inbound:
    """A ROS 2 topic the bridge subscribes to and what it becomes on zendock's side."""

    ros_topic: str
    ros_type: str
    owner: str
    zendock_type: type[Message]


INBOUND: tuple[Inbound, ...] = (
    Inbound(topics.CMD_VEL, TWIST, "simulator", Twist),
    Inbound(topics.CMD_VEL, TWIST_STAMPED, "simulator", Twist),
    Inbound(GOAL_POSE, "geometry_msgs/msg/PoseStamped", "planner", PoseStamped),
    # zendock's localiser is the simulator's (map -> odom): it takes the estimate.
    Inbound(
        INITIAL_POSE, "geometry_msgs/msg/PoseWithCovarianceStamped", "simulator", PoseWithCovarianceStamped
    ),
)


def default_domain_id() -> int:
    """The ROS 2 domain both faces join unless told: ``ROS_DOMAIN_ID``, else 0 (as rcl reads it)."""
    raw = os.environ.get("ROS_DOMAIN_ID", "").strip()
    return int(raw) if raw.isdigit() else 0
