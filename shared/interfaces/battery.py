"""``zendock_msgs/srv/SetBatteryState``: put the simulated battery where a test or a demo needs it.

Every numeric field is optional in the ROS way: NaN leaves that value as it is. ``frozen`` is always
applied (a request without it thaws the battery). The server answers with the state it now has, or
an error naming the field it refused.
"""

from __future__ import annotations

import math
from dataclasses import field
from typing import Annotated

from shared.interface_types import ServiceType
from shared.messages import BatteryState
from shared.schema import FloatAny, Message, message
from shared.schema import Range as Bounds


@message("zendock_msgs/srv/SetBatteryState_Request")
class SetBatteryStateRequest(Message):
    """``percentage`` 0..1; ``drain_scale`` / ``charge_scale`` >= 0 (the charge moves that many times
    faster than the current alone would move it); ``frozen`` holds the percentage where it is."""

    percentage: Annotated[FloatAny, Bounds(0.0, 1.0)] = math.nan
    drain_scale: FloatAny = math.nan
    charge_scale: FloatAny = math.nan
    frozen: bool = False


@message("zendock_msgs/srv/SetBatteryState_Response")
class SetBatteryStateResponse(Message):
    """The battery after the change: the message it would publish now, and the knobs in force."""

    state: BatteryState = field(default_factory=BatteryState)
    drain_scale: float = 1.0
    charge_scale: float = 1.0
    frozen: bool = False


SET_BATTERY_STATE: ServiceType[SetBatteryStateRequest, SetBatteryStateResponse] = ServiceType(
    "zendock_msgs/srv/SetBatteryState", SetBatteryStateRequest, SetBatteryStateResponse
)
