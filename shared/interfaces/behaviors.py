"""The planner's behaviours, mirroring nav2_msgs' Spin, BackUp, DriveOnHeading, Wait and AssistedTeleop
actions.

Nav2's behavior_server runs these short motions (and a robot's recoveries). zendock's planner serves them
under the same names and Jazzy's fields, with Nav2's error codes (700s spin, 710s back-up, 720s drive on
heading) and an ``error_msg`` that says why.
"""

from __future__ import annotations

import enum
from dataclasses import field

from shared.interface_types import ActionType
from shared.messages import Duration, Point
from shared.schema import Message, UInt16, message


class SpinErrorCode(enum.IntEnum):
    NONE = 0
    UNKNOWN = 700
    TIMEOUT = 701
    TF_ERROR = 702
    COLLISION_AHEAD = 703


class BackUpErrorCode(enum.IntEnum):
    NONE = 0
    UNKNOWN = 710
    TIMEOUT = 711
    TF_ERROR = 712
    INVALID_INPUT = 713
    COLLISION_AHEAD = 714


class DriveOnHeadingErrorCode(enum.IntEnum):
    NONE = 0
    UNKNOWN = 720
    TIMEOUT = 721
    TF_ERROR = 722
    COLLISION_AHEAD = 723
    INVALID_INPUT = 724


@message("nav2_msgs/action/Spin_Goal")
class SpinGoal(Message):
    #: How far to turn (rad), counter-clockwise positive: relative to where the robot faces.
    target_yaw: float = 0.0
    time_allowance: Duration = field(default_factory=Duration)


@message("nav2_msgs/action/Spin_Result")
class SpinResult(Message):
    total_elapsed_time: Duration = field(default_factory=Duration)
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/Spin_Feedback")
class SpinFeedback(Message):
    angular_distance_traveled: float = 0.0


@message("nav2_msgs/action/BackUp_Goal")
class BackUpGoal(Message):
    #: ``target.x``: how far to reverse (m; its sign is ignored, as Nav2 does); y and z must be 0.
    target: Point = field(default_factory=Point)
    speed: float = 0.0
    time_allowance: Duration = field(default_factory=Duration)


@message("nav2_msgs/action/BackUp_Result")
class BackUpResult(Message):
    total_elapsed_time: Duration = field(default_factory=Duration)
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/BackUp_Feedback")
class BackUpFeedback(Message):
    distance_traveled: float = 0.0


@message("nav2_msgs/action/DriveOnHeading_Goal")
class DriveOnHeadingGoal(Message):
    #: ``target.x``: how far to drive straight (m), forwards when positive; ``speed`` has the same sign.
    target: Point = field(default_factory=Point)
    speed: float = 0.0
    time_allowance: Duration = field(default_factory=Duration)


@message("nav2_msgs/action/DriveOnHeading_Result")
class DriveOnHeadingResult(Message):
    total_elapsed_time: Duration = field(default_factory=Duration)
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/DriveOnHeading_Feedback")
class DriveOnHeadingFeedback(Message):
    distance_traveled: float = 0.0


@message("nav2_msgs/action/Wait_Goal")
class WaitGoal(Message):
    time: Duration = field(default_factory=Duration)


@message("nav2_msgs/action/Wait_Result")
class WaitResult(Message):
    total_elapsed_time: Duration = field(default_factory=Duration)
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/Wait_Feedback")
class WaitFeedback(Message):
    time_left: Duration = field(default_factory=Duration)


SPIN = ActionType("nav2_msgs/action/Spin", SpinGoal, SpinResult, SpinFeedback)
BACK_UP = ActionType("nav2_msgs/action/BackUp", BackUpGoal, BackUpResult, BackUpFeedback)
DRIVE_ON_HEADING = ActionType(
    "nav2_msgs/action/DriveOnHeading", DriveOnHeadingGoal, DriveOnHeadingResult, DriveOnHeadingFeedback
)
WAIT = ActionType("nav2_msgs/action/Wait", WaitGoal, WaitResult, WaitFeedback)


class AssistedTeleopErrorCode(enum.IntEnum):
    NONE = 0
    UNKNOWN = 730
    TIMEOUT = 731
    TF_ERROR = 732


@message("nav2_msgs/action/AssistedTeleop_Goal")
class AssistedTeleopGoal(Message):
    time_allowance: Duration = field(default_factory=Duration)


@message("nav2_msgs/action/AssistedTeleop_Result")
class AssistedTeleopResult(Message):
    total_elapsed_time: Duration = field(default_factory=Duration)
    error_code: UInt16 = 0
    error_msg: str = ""


@message("nav2_msgs/action/AssistedTeleop_Feedback")
class AssistedTeleopFeedback(Message):
    current_teleop_duration: Duration = field(default_factory=Duration)


ASSISTED_TELEOP = ActionType(
    "nav2_msgs/action/AssistedTeleop", AssistedTeleopGoal, AssistedTeleopResult, AssistedTeleopFeedback
)
