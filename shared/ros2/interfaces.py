"""The ROS 2 interfaces zendock serves beyond Jazzy's common ones: its actions, as rosidl expands them.

rosidl turns an action ``pkg/action/Name`` into messages (``Name_Goal``, ``Name_Result``,
``Name_Feedback``, ``Name_FeedbackMessage``) and two services (``Name_SendGoal``, ``Name_GetResult``);
cancelling uses ``action_msgs/srv/CancelGoal``. A service ``S`` is itself described by a type with the
fields ``request_message``, ``response_message`` and ``event_message`` (``S_Event``: the call's
``service_msgs/msg/ServiceEventInfo`` and at most one request and one response); its RIHS01 hash, the one
rmw_zenoh puts in the service's key, is that type's hash. The definitions below are those of Nav2's
``nav2_msgs`` and ``opennav_docking_msgs`` for Jazzy (field names and types; comments left out).
"""

from __future__ import annotations

from typing import Any

from rosbags.typesys import get_types_from_msg

#: Field definitions as rosbags keeps them: type name -> (constants, fields).
TypeDefs = dict[str, tuple[list[Any], list[Any]]]

NAVIGATE_TO_POSE = "nav2_msgs/action/NavigateToPose"
DOCK_ROBOT = "opennav_docking_msgs/action/DockRobot"
UNDOCK_ROBOT = "opennav_docking_msgs/action/UndockRobot"
CANCEL_GOAL = "action_msgs/srv/CancelGoal"

#: goal, result, feedback of each action (``.action`` text split at ``---``).
ACTIONS: dict[str, tuple[str, str, str]] = {
    NAVIGATE_TO_POSE: (
        "geometry_msgs/PoseStamped pose\nstring behavior_tree",
        "uint16 error_code\nstring error_msg",
        "geometry_msgs/PoseStamped current_pose\nbuiltin_interfaces/Duration navigation_time\n"
        "builtin_interfaces/Duration estimated_time_remaining\nint16 number_of_recoveries\nfloat32 distance_remaining",
    ),
    DOCK_ROBOT: (
        "bool use_dock_id\nstring dock_id\ngeometry_msgs/PoseStamped dock_pose\nstring dock_type\n"
        "float32 max_staging_time\nbool navigate_to_staging_pose",
        "bool success\nuint16 error_code\nuint16 num_retries",
        "uint16 state\nbuiltin_interfaces/Duration docking_time\nuint16 num_retries",
    ),
    UNDOCK_ROBOT: (
        "string dock_type\nfloat32 max_undocking_time",
        "bool success\nuint16 error_code",
        "",
    ),
}

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
    defs.update(_service(CANCEL_GOAL, _CANCEL_REQUEST, _CANCEL_RESPONSE))
    for action, (goal, result, feedback) in ACTIONS.items():
        defs.update(_messages(goal, f"{action}_Goal"))
        defs.update(_messages(result, f"{action}_Result"))
        defs.update(_messages(feedback, f"{action}_Feedback"))
        defs.update(_service(f"{action}_SendGoal", f"unique_identifier_msgs/UUID goal_id\n{action}_Goal goal",
                             "bool accepted\nbuiltin_interfaces/Time stamp"))
        defs.update(_service(f"{action}_GetResult", "unique_identifier_msgs/UUID goal_id",
                             f"int8 status\n{action}_Result result"))
        defs.update(_messages(f"unique_identifier_msgs/UUID goal_id\n{action}_Feedback feedback",
                              f"{action}_FeedbackMessage"))
    return defs


def _service(service: str, request: str, response: str) -> TypeDefs:
    request_type, response_type = service_parts(service)
    defs = _messages(request, request_type)
    defs.update(_messages(response, response_type))
    defs.update(_messages(f"service_msgs/ServiceEventInfo info\n{request_type}[<=1] request\n"
                          f"{response_type}[<=1] response", f"{service}_Event"))
    defs.update(_messages(f"{request_type} request_message\n{response_type} response_message\n"
                          f"{service}_Event event_message", service))
    return defs


def _messages(text: str, name: str) -> TypeDefs:
    parsed = get_types_from_msg(text.strip() or _EMPTY, name)
    return {_own_name(n): (consts, [(f, _own_desc(d)) for f, d in fields]) for n, (consts, fields) in parsed.items()}


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
