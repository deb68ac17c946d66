"""Mistakes on the command line: one line naming the cause, exit 2, no traceback, nothing started."""

from __future__ import annotations

import importlib.metadata
from pathlib import Path

import pytest

from deploy.cli import main

REPO_ROOT = Path(__file__).resolve().parents[3]


def _exit_code(argv: list[str]) -> int:
    """``main(argv)``'s exit code, whether it returns one or argparse exits."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)


def _one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert "Traceback" not in captured.err
    return lines[-1]


@pytest.fixture(autouse=True)
def _nothing_starts(monkeypatch: pytest.MonkeyPatch) -> None:
    """A validation error must come before any stack: starting one fails the test."""
    import deploy.demo  # noqa: PLC0415

    def refuse(*_args: object, **_kwargs: object) -> None:
        raise AssertionError("the demo started before its arguments were checked")

    monkeypatch.setattr(deploy.demo, "run_demo", refuse)
    monkeypatch.chdir(REPO_ROOT)


@pytest.mark.parametrize(
    ("start", "expected"),
    [
        (["100", "100", "0"], "--start (100, 100) is outside the bounds [-3.0, 0.43, 3.0, 5.0]"),
        (["-2", "3.8", "0"], "--start (-2, 3.8) puts the robot into boxes.0"),
        (["-1", "0.7", "0"], "puts the robot into"),
        (["nan", "1", "0"], "--start (nan, 1.0) is not finite"),
    ],
)
def test_demo_checks_the_start_pose_against_the_world(start: list[str], expected: str,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    assert _exit_code(["demo", "--start", *start]) == 2
    line = _one_error_line(capsys)
    assert line.startswith("zendock demo: ") and expected in line and "seed_room.yaml" in line


def test_demo_rejects_a_misspelt_world_key_before_starting(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    world = tmp_path / "room.yaml"
    world.write_text("name: room\nbounds: [0, 0, 4, 3]\nwals: [[[1, 0], [1, 1]]]\n")
    assert _exit_code(["demo", "--world", str(world)]) == 2
    assert _one_error_line(capsys) == f"zendock demo: {world}: wals: unknown key"


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["trials", "--n", "abc"], "argument --n: must be a whole number of at least 1, got 'abc'"),
        (["trials", "--workers", "0"], "argument --workers: must be a whole number of at least 1, got '0'"),
        (["demo", "--rtf", "fast"], "argument --rtf: must be a positive number or max, got 'fast'"),
        (["demo", "--timeout", "soon"], "argument --timeout: must be a positive number, got 'soon'"),
        (["fleet", "--robots", "two"], "argument --robots: must be a whole number of at least 1, got 'two'"),
        (["fleet", "--duration", "-5"], "argument --duration: must be a positive number, got '-5'"),
        (["fleet", "--resume-at", "most"], "argument --resume-at: must be a fraction"),
    ],
)
def test_bad_values_are_named_for_users_not_by_parser_functions(argv: list[str], expected: str,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    assert _exit_code(argv) == 2
    line = _one_error_line(capsys)
    assert expected in line and "_count" not in line and "_rtf" not in line and "invalid" not in line


def test_version_comes_from_the_package_metadata(capsys: pytest.CaptureFixture[str]) -> None:
    assert _exit_code(["--version"]) == 0
    assert capsys.readouterr().out == f"zendock {importlib.metadata.version('zendock')}\n"
