"""Docking result codes, feedback states and the exception raised for an unusable dock.

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
    """A dock the request cannot use (not in the database, not valid), raised where the dock is looked up.

    It is the one exception of docking: the runs catch it where they choose the dock and end the action
    through their single failure path (``_fail`` / ``_end``) with its ``error_code``; every other failure
    is reported there directly with its code.
    """

    def __init__(self, error_code: DockingErrorCode, message: str) -> None:
        super().__init__(message)
        self.error_code = error_code
