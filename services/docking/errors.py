"""Docking result codes, feedback states and the exceptions that carry them.

The numbers mirror Nav2's ``nav2_msgs/action/DockRobot.action`` so a client that knows Nav2's codes reads
zendock's results unchanged. ``GOAL_REJECTED``, ``SEND_GOAL_FAILURE`` and ``TIMEOUT`` exist in recent
Nav2 releases (not in the first opennav_docking_msgs version) and are kept with the same values.
"""

from __future__ import annotations

from enum import IntEnum


class DockingErrorCode(IntEnum):
    """``DockRobot`` result ``error_code``; the order of the 9xx codes is their priority, as in Nav2."""

    NONE = 0
    GOAL_REJECTED = 1
    SEND_GOAL_FAILURE = 2
    DOCK_NOT_IN_DB = 901
    DOCK_NOT_VALID = 902
    FAILED_TO_STAGE = 903
    FAILED_TO_DETECT_DOCK = 904
    FAILED_TO_CONTROL = 905
    FAILED_TO_CHARGE = 906
    TIMEOUT = 907
    UNKNOWN = 999


class DockingState(IntEnum):
    """``DockRobot`` feedback ``state``: which step of the docking sequence runs now."""

    NONE = 0
    NAV_TO_STAGING_POSE = 1
    INITIAL_PERCEPTION = 2
    CONTROLLING = 3
    WAIT_FOR_CHARGE = 4
    RETRY = 5


class DockingError(Exception):
    """A docking failure; ``error_code`` is what the action result reports."""

    error_code: DockingErrorCode = DockingErrorCode.UNKNOWN


class DockNotInDbError(DockingError, LookupError):
    """The requested dock id is not in the dock database."""

    error_code = DockingErrorCode.DOCK_NOT_IN_DB


class DockNotValidError(DockingError):
    """The request names no usable dock (unknown dock type, empty database, bad pose)."""

    error_code = DockingErrorCode.DOCK_NOT_VALID


class FailedToStageError(DockingError):
    """Navigation to the staging pose failed."""

    error_code = DockingErrorCode.FAILED_TO_STAGE


class FailedToDetectDockError(DockingError):
    """The dock was not seen in time (initial perception) or was lost while approaching."""

    error_code = DockingErrorCode.FAILED_TO_DETECT_DOCK


class FailedToControlError(DockingError):
    """The approach did not reach the dock in time or the controller could not produce a command."""

    error_code = DockingErrorCode.FAILED_TO_CONTROL


class FailedToChargeError(DockingError):
    """The robot is on the dock but charging did not start in time."""

    error_code = DockingErrorCode.FAILED_TO_CHARGE


class DockingTimeoutError(DockingError):
    """The whole action exceeded its time budget."""

    error_code = DockingErrorCode.TIMEOUT
