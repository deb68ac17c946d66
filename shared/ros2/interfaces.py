"""The ROS 2 interfaces zendock serves beyond Jazzy's common ones: its actions, as rosidl expands them.

rosidl turns an action ``pkg/action/Name`` into messages (``Name_Goal``, ``Name_Result``,
``Name_Feedback``, ``Name_FeedbackMessage``) and two services (``Name_SendGoal``, ``Name_GetResult``);
cancelling uses ``action_msgs/srv/CancelGoal``. A service ``S`` is itself described by a type with the
fields ``request_message``, ``response_message`` and ``event_message`` (``S_Event``: the call's
``service_msgs/msg/ServiceEventInfo`` and at most one request and one response); its RIHS01 hash, the one
rmw_zenoh puts in the service's key, is that type's hash. The actions are Nav2's for Jazzy, read from
their ``.action`` files in ``definitions/`` (in Jazzy the docking actions live in ``nav2_msgs``).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

#: Field definitions as rosbags keeps them: type name -> (constants, fields).
TypeDefs = dict[str, tuple[list[Any], list[Any]]]

NAVIGATE_TO_POSE = "nav2_msgs/action/NavigateToPose"
DOCK_ROBOT = "nav2_msgs/action/DockRobot"
UNDOCK_ROBOT = "nav2_msgs/action/UndockRobot"
NAVIGATE_THROUGH_POSES = "nav2_msgs/action/NavigateThroughPoses"
FOLLOW_WAYPOINTS = "nav2_msgs/action/FollowWaypoints"
FOLLOW_GPS_WAYPOINTS = "nav2_msgs/action/FollowGPSWaypoints"
COMPUTE_PATH_TO_POSE = "nav2_msgs/action/ComputePathToPose"
COMPUTE_PATH_THROUGH_POSES = "nav2_msgs/action/ComputePathThroughPoses"
SMOOTH_PATH = "nav2_msgs/action/SmoothPath"
FOLLOW_PATH = "nav2_msgs/action/FollowPath"
SPIN = "nav2_msgs/action/Spin"
BACK_UP = "nav2_msgs/action/BackUp"
DRIVE_ON_HEADING = "nav2_msgs/action/DriveOnHeading"
WAIT = "nav2_msgs/action/Wait"
ASSISTED_TELEOP = "nav2_msgs/action/AssistedTeleop"
CANCEL_GOAL = "action_msgs/srv/CancelGoal"
ACTIONS = (
    NAVIGATE_TO_POSE,
    DOCK_ROBOT,
    UNDOCK_ROBOT,
    NAVIGATE_THROUGH_POSES,
    FOLLOW_WAYPOINTS,
    FOLLOW_GPS_WAYPOINTS,
    COMPUTE_PATH_TO_POSE,
    COMPUTE_PATH_THROUGH_POSES,
    SMOOTH_PATH,
    FOLLOW_PATH,
    SPIN,
    BACK_UP,
    DRIVE_ON_HEADING,
    WAIT,
    ASSISTED_TELEOP,
)
GET_COSTMAP = "nav2_msgs/srv/GetCostmap"
CLEAR_ENTIRE_COSTMAP = "nav2_msgs/srv/ClearEntireCostmap"
LOAD_MAP = "nav2_msgs/srv/LoadMap"
MANAGE_LIFECYCLE_NODES = "nav2_msgs/srv/ManageLifecycleNodes"
#: Nav2's ``.action``, ``.srv`` and ``.msg`` files, shipped with their licence notice (see the README there).
DEFINITIONS = Path(__file__).parent / "definitions"


def package_messages(package: str) -> TypeDefs:
    """Every ``msg/*.msg`` of ``package`` in :data:`DEFINITIONS` (a name in the same package may be bare)."""
    defs: TypeDefs = {}
    for path in sorted((DEFINITIONS / package / "msg").glob("*.msg")):
        defs.update(_messages(path.read_text(encoding="utf-8"), f"{package}/msg/{path.stem}"))
    return defs


def package_services(package: str) -> TypeDefs:
    """Every ``srv/*.srv`` of ``package`` in :data:`DEFINITIONS`, with its description types."""
    defs: TypeDefs = {}
    for path in sorted((DEFINITIONS / package / "srv").glob("*.srv")):
        sections = re.split(r"^---\s*$", path.read_text(encoding="utf-8"), flags=re.MULTILINE)
        if len(sections) != 2:
            raise ValueError(f"{path}: a service has a request and a response separated by '---'")
        defs.update(service_definitions(f"{package}/srv/{path.stem}", sections[0], sections[1]))
    return defs


def action_text(action: str) -> tuple[str, str, str]:
    """Goal, result and feedback of an action, from its ``.action`` file (split at the ``---`` lines)."""
    package, _, name = action.partition("/action/")
    path = DEFINITIONS / package / "action" / f"{name}.action"
    sections = re.split(r"^---\s*$", path.read_text(encoding="utf-8"), flags=re.MULTILINE)
    if len(sections) != 3:
        raise ValueError(f"{path}: an action has goal, result and feedback separated by '---'")
    return sections[0], sections[1], sections[2]


#: lifecycle_msgs/srv/GetState (rcl_interfaces): what Nav2 scripts poll (:mod:`shared.nav2_stand_ins`).
GET_STATE = "lifecycle_msgs/srv/GetState"
_GET_STATE_RESPONSE = "lifecycle_msgs/State current_state"
#: lifecycle_msgs/srv/ChangeState (rcl_interfaces): what Nav2's lifecycle managers ask of each node.
CHANGE_STATE = "lifecycle_msgs/srv/ChangeState"
#: rcl_interfaces' parameter services (every ROS 2 node's ``~/<name>``): name -> (type, request, response).
PARAMETER_SERVICES: dict[str, tuple[str, str, str]] = {
    "list_parameters": (
        "rcl_interfaces/srv/ListParameters",
        "uint64 DEPTH_RECURSIVE=0\nstring[] prefixes\nuint64 depth",
        "rcl_interfaces/ListParametersResult result",
    ),
    "get_parameters": (
        "rcl_interfaces/srv/GetParameters",
        "string[] names",
        "rcl_interfaces/ParameterValue[] values",
    ),
    "set_parameters": (
        "rcl_interfaces/srv/SetParameters",
        "rcl_interfaces/Parameter[] parameters",
        "rcl_interfaces/SetParametersResult[] results",
    ),
    "set_parameters_atomically": (
        "rcl_interfaces/srv/SetParametersAtomically",
        "rcl_interfaces/Parameter[] parameters",
        "rcl_interfaces/SetParametersResult result",
    ),
    "describe_parameters": (
        "rcl_interfaces/srv/DescribeParameters",
        "string[] names",
        "rcl_interfaces/ParameterDescriptor[] descriptors",
    ),
    "get_parameter_types": ("rcl_interfaces/srv/GetParameterTypes", "string[] names", "uint8[] types"),
}
#: action_msgs/srv/CancelGoal (rcl_interfaces), request and response.
_CANCEL_REQUEST = "action_msgs/GoalInfo goal_info"
_CANCEL_RESPONSE = "int8 return_code\naction_msgs/GoalInfo[] goals_canceling"
#: rosidl's stand-in member of an empty structure.
_EMPTY = "uint8 structure_needs_at_least_one_member"


def service_parts(service: str) -> tuple[str, str]:
    """The request and response message types of a service type."""
    return f"{service}_Request", f"{service}_Response"


def action_parts(action: str) -> dict[str, str]:
    """The service and message types an action is carried by, by role."""
    return {
        "send_goal": f"{action}_SendGoal",
        "get_result": f"{action}_GetResult",
        "cancel_goal": CANCEL_GOAL,
        "feedback": f"{action}_FeedbackMessage",
        "status": "action_msgs/msg/GoalStatusArray",
    }


def definitions() -> TypeDefs:
    """Every type above (and the services' description types), ready for a rosbags type store."""
    defs: TypeDefs = {}
    defs.update(service_definitions(CANCEL_GOAL, _CANCEL_REQUEST, _CANCEL_RESPONSE))
    defs.update(package_messages("geographic_msgs"))
    defs.update(package_messages("nav2_msgs"))
    defs.update(package_services("nav2_msgs"))
    defs.update(service_definitions(GET_STATE, "", _GET_STATE_RESPONSE))
    defs.update(service_definitions(CHANGE_STATE, "lifecycle_msgs/Transition transition", "bool success"))
    for service, request, response in PARAMETER_SERVICES.values():
        defs.update(service_definitions(service, request, response))
    for action in ACTIONS:
        goal, result, feedback = action_text(action)
        defs.update(_messages(goal, f"{action}_Goal"))
        defs.update(_messages(result, f"{action}_Result"))
        defs.update(_messages(feedback, f"{action}_Feedback"))
        defs.update(
            service_definitions(
                f"{action}_SendGoal",
                f"unique_identifier_msgs/UUID goal_id\n{action}_Goal goal",
                "bool accepted\nbuiltin_interfaces/Time stamp",
            )
        )
        defs.update(
            service_definitions(
                f"{action}_GetResult",
                "unique_identifier_msgs/UUID goal_id",
                f"int8 status\n{action}_Result result",
            )
        )
        defs.update(
            _messages(
                f"unique_identifier_msgs/UUID goal_id\n{action}_Feedback feedback",
                f"{action}_FeedbackMessage",
            )
        )
    return _bare_names_to_messages(defs)


def _bare_names_to_messages(defs: TypeDefs) -> TypeDefs:
    """A bare type name in a ``.srv`` or ``.action`` file (``MissedWaypoint[] missed_waypoints``) is the
    package's message (``nav2_msgs/msg/MissedWaypoint``), as rosidl reads it; rosbags files it beside the
    service or action (``nav2_msgs/action/MissedWaypoint``), which names no type."""

    def fixed(desc: Any) -> Any:
        kind, detail = desc
        if kind == 2 and detail not in defs:
            package, _, name = detail.rpartition("/")
            message = f"{package.rsplit('/', 1)[0]}/msg/{name}"
            return (kind, message) if message in defs else desc
        if kind in (3, 4):
            return kind, (fixed(detail[0]), detail[1])
        return desc

    return {name: (consts, [(f, fixed(d)) for f, d in fields]) for name, (consts, fields) in defs.items()}


def service_definitions(service: str, request: str, response: str) -> TypeDefs:
    """A service's request, response, event and description types from its request and response text."""
    request_type, response_type = service_parts(service)
    defs = _messages(request, request_type)
    defs.update(_messages(response, response_type))
    defs.update(
        _messages(
            f"service_msgs/ServiceEventInfo info\n{request_type}[<=1] request\n{response_type}[<=1] response",
            f"{service}_Event",
        )
    )
    defs.update(
        _messages(
            f"{request_type} request_message\n{response_type} response_message\n"
            f"{service}_Event event_message",
            service,
        )
    )
    return defs


def _messages(text: str, name: str) -> TypeDefs:
    # rosbags' parser only when definitions are read: the DDS face needs the names above, never the
    # definitions (its rclpy has the types built in), and starts lighter without it.
    from rosbags.typesys import get_types_from_msg  # noqa: PLC0415

    has_fields = any(line.split("#", 1)[0].strip() for line in text.splitlines())
    parsed = get_types_from_msg(text if has_fields else _EMPTY, name)
    return {
        _own_name(n): (consts, [(f, _own_desc(d)) for f, d in fields])
        for n, (consts, fields) in parsed.items()
    }


def _own_name(name: str) -> str:
    """rosbags files ``pkg/srv/X`` and ``pkg/action/X`` under ``pkg/srv/msg/X``; ROS 2 names them ``pkg/srv/X``."""
    return name.replace("/srv/msg/", "/srv/").replace("/action/msg/", "/action/")


def _own_desc(desc: Any) -> Any:
    kind, detail = desc
    if kind == 2:
        return kind, _own_name(detail)
    if kind in (3, 4):
        return kind, (_own_desc(detail[0]), detail[1])
    return desc
