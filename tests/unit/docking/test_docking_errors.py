from services.docking.errors import DockingError, DockingErrorCode, DockingState


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


def test_the_one_docking_exception_carries_its_code() -> None:
    err = DockingError(DockingErrorCode.DOCK_NOT_IN_DB, "why")
    assert err.error_code == DockingErrorCode.DOCK_NOT_IN_DB and str(err) == "why"
