"""Mistakes on the command line: one line naming the cause, exit 2, no traceback, nothing started."""

from __future__ import annotations

import importlib.metadata
import signal
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
    import deploy.demo

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
def test_demo_checks_the_start_pose_against_the_world(
    start: list[str], expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _exit_code(["demo", "--start", *start]) == 2
    line = _one_error_line(capsys)
    assert line.startswith("zendock demo: ") and expected in line and "seed_room.yaml" in line


def test_demo_rejects_a_misspelt_world_key_before_starting(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = tmp_path / "room.yaml"
    world.write_text("name: room\nbounds: [0, 0, 4, 3]\nwals: [[[1, 0], [1, 1]]]\n")
    assert _exit_code(["demo", "--world", str(world)]) == 2
    assert _one_error_line(capsys) == f"zendock demo: {world}: wals: unknown key (did you mean walls?)"


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
        (["worlds", "generate", "--seed", "-1"], "argument --seed: must be a whole number of at least 0"),
        (["worlds", "generate", "--out", "README.md"], "--out README.md: not a directory"),
        (["worlds", "generate", "--out", "README.md/x"], "--out README.md/x: cannot write rooms there"),
        (["trials", "--world", "generated:glas"], "no kind of generated world 'glas' (did you mean glass?)"),
    ],
)
def test_bad_values_are_named_for_users_not_by_parser_functions(
    argv: list[str], expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _exit_code(argv) == 2
    line = _one_error_line(capsys)
    assert expected in line and "_count" not in line and "_rtf" not in line and "invalid" not in line


def test_version_comes_from_the_package_metadata(capsys: pytest.CaptureFixture[str]) -> None:
    assert _exit_code(["--version"]) == 0
    assert capsys.readouterr().out == f"zendock {importlib.metadata.version('zendock')}\n"


def test_ps_outside_a_project_says_there_is_no_stack_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ZENDOCK_STACK_FILE", raising=False)
    assert _exit_code(["ps"]) == 2
    assert _one_error_line(capsys).startswith("zendock ps: no stack file: pass -f FILE")
    assert _exit_code(["ps", "-f", "nope.yaml"]) == 2
    assert _one_error_line(capsys) == "zendock ps: nope.yaml: no such stack file"


def test_logs_of_a_service_the_stack_does_not_have(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ZENDOCK_STACK_FILE", raising=False)
    (tmp_path / "stack.yaml").write_text("name: t\nservices:\n  a: {command: [x]}\n  b: {command: [y]}\n")
    assert _exit_code(["logs", "nosuch"]) == 2
    assert _one_error_line(capsys) == "zendock logs: no such service: nosuch (services: a, b)"
    assert _exit_code(["logs", "a"]) == 1  # a service of the stack that has not run yet
    assert "no logs for a" in _one_error_line(capsys)


def test_kill_says_what_it_did() -> None:
    from deploy.commands.lifecycle import _kill_line
    from deploy.launcher.status import ServiceStatus

    running = ServiceStatus("battery", "running", 4242, 0, "healthy")
    assert (
        _kill_line("battery", running, True, signal.SIGKILL)
        == "battery: killed (SIGKILL to pid 4242; its restart policy applies)"
    )
    assert _kill_line("battery", running, True, signal.SIGINT) == "battery: sent SIGINT to pid 4242"
    exited = ServiceStatus("map", "exited", None, 0, "none")
    assert _kill_line("map", exited, False, signal.SIGKILL) == "map: not running (exited), no signal sent"


def test_trials_merge_names_itself_once(capsys: pytest.CaptureFixture[str]) -> None:
    assert _exit_code(["trials", "merge", "no/such/shard"]) == 2
    line = _one_error_line(capsys)
    assert line == "zendock trials merge: no/such/shard: no such file or directory", line


@pytest.mark.parametrize(
    ("argv", "guess"),
    [
        (["up", "--profile", "ros2dds"], "--profile ros2dds (did you mean ros2-dds?)"),
        (["config", "--profile", "vizz", "--services"], "--profile vizz (did you mean viz?)"),
        (["up", "dockng"], "no such service: dockng (did you mean docking?)"),
        (["up", "--set", "dockng.auto_dock=false"], "no zendock service 'dockng' (did you mean docking?)"),
        (["logs", "dockng"], "no such service: dockng (did you mean docking?)"),
        (["ps", "dockng"], "no such service: dockng (did you mean docking?)"),
    ],
)
def test_a_misspelled_service_or_profile_names_itself(
    argv: list[str], guess: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import deploy.commands.up

    def refuse(*_args: object, **_kwargs: object) -> int:
        raise AssertionError(f"zendock {' '.join(argv)} started a stack")

    monkeypatch.setattr(deploy.commands.up, "run_foreground", refuse)
    monkeypatch.setattr(deploy.commands.up, "run_detached", refuse)
    assert _exit_code(argv) == 2
    line = _one_error_line(capsys)
    assert line.startswith(f"zendock {argv[0]}: ") and guess in line, line


def test_a_shard_count_is_bounded_by_the_whole_campaigns_trials(capsys: pytest.CaptureFixture[str]) -> None:
    """A campaign across worlds is sharded as a whole: one trial in each unseen room makes that many."""
    rooms = len(list((REPO_ROOT / "deploy" / "worlds" / "unseen").glob("*.yaml")))
    assert _exit_code(["trials", "--world", "deploy/worlds/unseen", "--n", "1", "--shard", "1/30"]) == 2
    line = _one_error_line(capsys)
    assert line == f"zendock trials: --shard 1/30: {rooms} trials cannot make 30 shards", line


def test_help_shows_the_defaults_an_option_has(capsys: pytest.CaptureFixture[str]) -> None:
    assert _exit_code(["trials", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "number of dockings (per world; with generated:KIND, of rooms) (default: 10)" in text
    assert "(default: 0)" in text, "a zero default is a default worth showing"
    assert "(default: None)" not in text and "(default: False)" not in text
