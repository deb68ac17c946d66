"""Nav2's lifecycle requests: ``lifecycle_msgs``' ``GetState`` and ``ChangeState``, and
``nav2_msgs/srv/ManageLifecycleNodes``.

Nav2's servers are lifecycle nodes; a script's ``waitUntilNav2Active()`` asks ``amcl/get_state`` and
``bt_navigator/get_state`` until each says ``active``, and ``lifecycleStartup()`` / ``lifecycleShutdown()``
ask each lifecycle manager's ``manage_nodes``. Which zendock service stands in for which Nav2 node is
:mod:`shared.nav2_stand_ins`; the states and what a command does are :mod:`shared.lifecycle`.
"""

from __future__ import annotations

from dataclasses import field
from typing import ClassVar

from shared.interface_types import ServiceType
from shared.schema import Message, UInt8, message


@message("lifecycle_msgs/msg/State")
class State(Message):
    """A lifecycle state: ``id`` one of the ``PRIMARY_STATE_*`` constants, ``label`` its name."""

    PRIMARY_STATE_UNKNOWN: ClassVar[int] = 0
    PRIMARY_STATE_UNCONFIGURED: ClassVar[int] = 1
    PRIMARY_STATE_INACTIVE: ClassVar[int] = 2
    PRIMARY_STATE_ACTIVE: ClassVar[int] = 3
    PRIMARY_STATE_FINALIZED: ClassVar[int] = 4

    id: UInt8 = 0
    label: str = ""


ACTIVE = State(id=State.PRIMARY_STATE_ACTIVE, label="active")
UNKNOWN = State(id=State.PRIMARY_STATE_UNKNOWN, label="unknown")


@message("lifecycle_msgs/srv/GetState_Request")
class GetStateRequest(Message):
    pass


@message("lifecycle_msgs/srv/GetState_Response")
class GetStateResponse(Message):
    current_state: State = field(default_factory=State)


@message("lifecycle_msgs/msg/Transition")
class Transition(Message):
    """A transition asked for: ``id`` one of :class:`shared.lifecycle.Transition`, ``label`` optional."""

    id: UInt8 = 0
    label: str = ""


@message("lifecycle_msgs/srv/ChangeState_Request")
class ChangeStateRequest(Message):
    transition: Transition = field(default_factory=Transition)


@message("lifecycle_msgs/srv/ChangeState_Response")
class ChangeStateResponse(Message):
    success: bool = False


@message("nav2_msgs/srv/ManageLifecycleNodes_Request")
class ManageLifecycleNodesRequest(Message):
    """``command``: one of :class:`shared.lifecycle.Command` (Nav2's constants below)."""

    STARTUP: ClassVar[int] = 0
    PAUSE: ClassVar[int] = 1
    RESUME: ClassVar[int] = 2
    RESET: ClassVar[int] = 3
    SHUTDOWN: ClassVar[int] = 4
    CONFIGURE: ClassVar[int] = 5
    CLEANUP: ClassVar[int] = 6

    command: UInt8 = 0


@message("nav2_msgs/srv/ManageLifecycleNodes_Response")
class ManageLifecycleNodesResponse(Message):
    success: bool = False


CHANGE_STATE: ServiceType[ChangeStateRequest, ChangeStateResponse] = ServiceType(
    "lifecycle_msgs/srv/ChangeState", ChangeStateRequest, ChangeStateResponse
)
MANAGE_LIFECYCLE_NODES: ServiceType[ManageLifecycleNodesRequest, ManageLifecycleNodesResponse] = ServiceType(
    "nav2_msgs/srv/ManageLifecycleNodes", ManageLifecycleNodesRequest, ManageLifecycleNodesResponse
)
GET_STATE: ServiceType[GetStateRequest, GetStateResponse] = ServiceType(
    "lifecycle_msgs/srv/GetState", GetStateRequest, GetStateResponse
)
