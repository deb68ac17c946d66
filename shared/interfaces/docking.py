"""The docking service's actions, mirroring opennav_docking_msgs: DockRobot and UndockRobot."""

from __future__ import annotations

from dataclasses import field
from typing import ClassVar

from shared.interface_types import ActionType
from shared.messages import Duration, PoseStamped
from shared.schema import Message, UInt16, message


@message("opennav_docking_msgs/action/DockRobot_Goal")
class DockRobotGoal(Message):
    """Dock at ``dock_id`` (``use_dock_id``) or at ``dock_pose``; empty id with use_dock_id picks the nearest."""

    use_dock_id: bool = True
    dock_id: str = ""
    dock_pose: PoseStamped = field(default_factory=PoseStamped)
    dock_type: str = ""
    max_staging_time: float = 1000.0
    navigate_to_staging_pose: bool = True


@message("opennav_docking_msgs/action/DockRobot_Result")
class DockRobotResult(Message):
    NONE: ClassVar[int] = 0
    DOCK_NOT_IN_DB: ClassVar[int] = 901
    DOCK_NOT_VALID: ClassVar[int] = 902
    FAILED_TO_STAGE: ClassVar[int] = 903
    FAILED_TO_DETECT_DOCK: ClassVar[int] = 904
    FAILED_TO_CONTROL: ClassVar[int] = 905
    FAILED_TO_CHARGE: ClassVar[int] = 906
    TIMEOUT: ClassVar[int] = 907
    UNKNOWN: ClassVar[int] = 999
    success: bool = False
    error_code: UInt16 = 0
    num_retries: UInt16 = 0


@message("opennav_docking_msgs/action/DockRobot_Feedback")
class DockRobotFeedback(Message):
    NONE: ClassVar[int] = 0
    NAV_TO_STAGING_POSE: ClassVar[int] = 1
    INITIAL_PERCEPTION: ClassVar[int] = 2
    CONTROLLING: ClassVar[int] = 3
    WAIT_FOR_CHARGE: ClassVar[int] = 4
    RETRY: ClassVar[int] = 5
    state: UInt16 = 0
    docking_time: Duration = field(default_factory=Duration)
    num_retries: UInt16 = 0


@message("opennav_docking_msgs/action/UndockRobot_Goal")
class UndockRobotGoal(Message):
    dock_type: str = ""
    max_undocking_time: float = 30.0


@message("opennav_docking_msgs/action/UndockRobot_Result")
class UndockRobotResult(Message):
    success: bool = False
    error_code: UInt16 = 0


@message("opennav_docking_msgs/action/UndockRobot_Feedback")
class UndockRobotFeedback(Message):
    pass


DOCK_ROBOT = ActionType(
    "opennav_docking_msgs/action/DockRobot", DockRobotGoal, DockRobotResult, DockRobotFeedback
)
UNDOCK_ROBOT = ActionType(
    "opennav_docking_msgs/action/UndockRobot", UndockRobotGoal, UndockRobotResult, UndockRobotFeedback
)
