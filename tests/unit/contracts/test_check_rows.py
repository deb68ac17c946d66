"""Every check of a conform run has its row: pass, FAIL, or "not run" with the reason."""

from __future__ import annotations

from deploy.contracts.checks import Check, PlannedCheck, run_in_turn, units_hint


def _rows(planned: list[PlannedCheck]) -> list[tuple[str, str, str]]:
    seen: list[Check] = []
    rows = run_in_turn(planned, seen.append)
    assert rows == seen  # each row is told as it is decided
    return [(row.name, row.result, row.evidence) for row in rows]


def test_a_service_that_does_not_start_leaves_every_other_row_not_run_and_saying_why() -> None:
    planned = [
        PlannedCheck("starts", lambda: (False, "exited with code 3"), stops_the_rest="it did not start"),
        PlannedCheck("publishes odom", lambda: (True, "20 Hz")),
        PlannedCheck("SIGTERM", lambda: (True, "exit 0")),
    ]
    assert _rows(planned) == [
        ("starts", "FAIL", "exited with code 3"),
        ("publishes odom", "not run", "not run: it did not start"),
        ("SIGTERM", "not run", "not run: it did not start"),
    ]


def test_a_check_whose_precondition_fails_reads_not_run_and_the_rest_go_on() -> None:
    ran: list[str] = []

    def restart() -> tuple[bool, str]:
        ran.append("restart")
        return True, "back after 0.8 s"

    planned = [
        PlannedCheck("starts", lambda: (True, "token"), stops_the_rest="it did not start"),
        PlannedCheck("publishes odom", lambda: (False, "nothing arrived")),  # not a gate: the rest go on
        PlannedCheck("SIGTERM", lambda: (True, "exit 0"), blocked=lambda: "it had already exited (code 1)"),
        PlannedCheck("restart", restart),
    ]
    assert _rows(planned) == [
        ("starts", "pass", "token"),
        ("publishes odom", "FAIL", "nothing arrived"),
        ("SIGTERM", "not run", "not run: it had already exited (code 1)"),
        ("restart", "pass", "back after 0.8 s"),
    ]
    assert ran == ["restart"]


def test_a_check_that_raises_fails_with_the_exception_named() -> None:
    def broken() -> tuple[bool, str]:
        raise TimeoutError("no reply in 5 s")

    (row,) = run_in_turn([PlannedCheck("answers teleport", broken)], lambda _row: None)
    assert (row.result, row.evidence) == ("FAIL", "TimeoutError: no reply in 5 s")
    assert row.as_dict()["result"] == "FAIL"


def test_a_distance_off_by_a_unit_says_which_unit() -> None:
    assert units_hint(1000.0, 1.0) == ": millimetres?"
    assert units_hint(98.0, 1.0) == ": centimetres?"
    assert units_hint(1.02, 1.0) == "" and units_hint(5.0, 1.0) == ""
    assert units_hint(30.0, 0.0) == ""  # no distance to compare with
