"""The simulator's requests: place a robot (tests, trials), read its ground truth, set what its localiser believes."""

from __future__ import annotations

from dataclasses import field

from shared.interface_types import ServiceType
from shared.messages import DockContact, Pose, Time
from shared.schema import Message, UInt32, message


@message("zendock_msgs/srv/Teleport_Request")
class TeleportRequest(Message):
    """Place the robot at ``(x, y, yaw)`` in the map frame, standing still, odometry restarted there.

    ``robot``: the robot's namespace when one simulator serves several ("" for the only robot).
    """

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    robot: str = ""


@message("zendock_msgs/srv/Teleport_Response")
class TeleportResponse(Message):
    success: bool = False
    message: str = ""


@message("zendock_msgs/srv/SimState_Request")
class SimStateRequest(Message):
    robot: str = ""


@message("zendock_msgs/srv/SimState_Response")
class SimStateResponse(Message):
    """Ground truth: the true pose, collision total, contact state, and the world's name."""

    stamp: Time = field(default_factory=Time)
    world: str = ""
    pose: Pose = field(default_factory=Pose)
    collisions: UInt32 = 0
    contact: DockContact = field(default_factory=DockContact)


@message("zendock_msgs/srv/SetLocalisation_Request")
class SetLocalisationRequest(Message):
    """Make the simulated localiser believe the robot stands at ``(x, y, yaw)`` in the map (what
    ``/initialpose`` asks of a ROS 2 localiser). The robot does not move; the belief's offset from the
    truth becomes the localisation error and stays (the simulated localiser does not converge back)."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    robot: str = ""


@message("zendock_msgs/srv/SetLocalisation_Response")
class SetLocalisationResponse(Message):
    success: bool = False
    message: str = ""


TELEPORT = ServiceType("zendock_msgs/srv/Teleport", TeleportRequest, TeleportResponse)
SIM_STATE = ServiceType("zendock_msgs/srv/SimState", SimStateRequest, SimStateResponse)
SET_LOCALISATION = ServiceType(
    "zendock_msgs/srv/SetLocalisation", SetLocalisationRequest, SetLocalisationResponse
)
