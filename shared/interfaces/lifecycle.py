"""``lifecycle_msgs/srv/GetState``: the lifecycle state Nav2 scripts poll before they start.

Nav2's servers are lifecycle nodes; a script's ``waitUntilNav2Active()`` asks ``amcl/get_state`` and
``bt_navigator/get_state`` until each says ``active``. zendock's services have no lifecycle: one that
serves is active. Which of them stands in for which Nav2 node is :mod:`shared.nav2_stand_ins`.
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


GET_STATE: ServiceType[GetStateRequest, GetStateResponse] = ServiceType(
    "lifecycle_msgs/srv/GetState", GetStateRequest, GetStateResponse
)
