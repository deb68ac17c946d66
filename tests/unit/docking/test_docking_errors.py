from services.docking.errors import (
    DockingError,
    DockingErrorCode,
    DockingState,
    DockingTimeoutError,
    DockNotInDbError,
    DockNotValidError,
    FailedToChargeError,
    FailedToControlError,
    FailedToDetectDockError,
    FailedToStageError,
)


def test_error_codes_match_dock_robot_action() -> None:
    assert {c.name: int(c) for c in DockingErrorCode} == {
        "NONE": 0,
        "GOAL_REJECTED": 1,
        "SEND_GOAL_FAILURE": 2,
        "DOCK_NOT_IN_DB": 901,
        "DOCK_NOT_VALID": 902,
        "FAILED_TO_STAGE": 903,
        "FAILED_TO_DETECT_DOCK": 904,
        "FAILED_TO_CONTROL": 905,
        "FAILED_TO_CHARGE": 906,
        "TIMEOUT": 907,
        "UNKNOWN": 999,
    }


def test_feedback_states_match_dock_robot_action() -> None:
    assert [(s.name, int(s)) for s in DockingState] == [
        ("NONE", 0),
        ("NAV_TO_STAGING_POSE", 1),
        ("INITIAL_PERCEPTION", 2),
        ("CONTROLLING", 3),
        ("WAIT_FOR_CHARGE", 4),
        ("RETRY", 5),
    ]


def test_each_exception_carries_its_code() -> None:
    pairs = {
        DockNotInDbError: 901,
        DockNotValidError: 902,
        FailedToStageError: 903,
        FailedToDetectDockError: 904,
        FailedToControlError: 905,
        FailedToChargeError: 906,
        DockingTimeoutError: 907,
        DockingError: 999,
    }
    for exc_type, code in pairs.items():
        err = exc_type("why")
        assert isinstance(err, DockingError)
        assert err.error_code == code
        assert str(err) == "why"
    assert issubclass(DockNotInDbError, LookupError)
