"""The foreground printer and the per-service log files (rotation, tail, follow, merge)."""

from __future__ import annotations

import io
import random
from collections import deque
from pathlib import Path

from deploy.launcher.logs import (
    Follower,
    LogLine,
    RotatingLog,
    RunFailure,
    failure_line,
    log_files,
    merge_by_time,
    parse_line,
    tail,
)
from deploy.launcher.printer import Printer


def test_printer_aligns_names_and_colours_only_when_asked() -> None:
    out = io.StringIO()
    printer = Printer(out, ["router", "simulator"], colour=False)
    printer.line("router", "listening")
    printer.line("simulator", "ready")
    assert out.getvalue() == "router    | listening\nsimulator | ready\n"
    coloured = io.StringIO()
    printer = Printer(coloured, ["a", "b"], colour=True)
    printer.line("a", "x")
    printer.line("b", "y")
    first, second = coloured.getvalue().splitlines()
    assert first.startswith("\033[") and first.endswith("a | \033[0mx")
    assert first.split("m", 1)[0] != second.split("m", 1)[0]


def test_printer_colour_follows_the_terminal_and_no_color(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.delenv("FORCE_COLOR", raising=False)
    assert Printer(io.StringIO(), []).colour is False
    monkeypatch.setenv("FORCE_COLOR", "1")
    assert Printer(io.StringIO(), []).colour is True
    monkeypatch.setenv("NO_COLOR", "1")
    assert Printer(io.StringIO(), []).colour is False


def test_logs_rotate_and_tail_reads_across_files(tmp_path: Path) -> None:
    log = RotatingLog(tmp_path / "sim.log", max_bytes=200, backups=2)
    for index in range(40):
        log.write(f"line {index}")
    log.close()
    files = log_files(tmp_path, "sim")
    assert [p.name for p in files] == ["sim.log.2", "sim.log.1", "sim.log"]
    assert all(p.stat().st_size < 200 + 40 for p in files)
    kept = [line.text for line in tail(tmp_path, "sim", None)]
    assert kept == [f"line {i}" for i in range(40 - len(kept), 40)]
    assert [line.text for line in tail(tmp_path, "sim", 3)] == ["line 37", "line 38", "line 39"]
    assert tail(tmp_path, "sim", 0) == []
    assert all(line.stamp.endswith("Z") for line in tail(tmp_path, "sim", 3))


def test_lines_parse_and_merge_by_time() -> None:
    parsed = parse_line("a", "2025-01-02T03:04:05.678Z hello world")
    assert parsed == LogLine("a", "2025-01-02T03:04:05.678Z", "hello world")
    assert parse_line("a", "no stamp") == LogLine("a", "", "no stamp")
    a = [LogLine("a", "2025-01-01T00:00:01.000Z", "a1"), LogLine("a", "2025-01-01T00:00:03.000Z", "a3")]
    b = [LogLine("b", "2025-01-01T00:00:02.000Z", "b2")]
    assert [line.text for line in merge_by_time([a, b])] == ["a1", "b2", "a3"]


def test_follower_sees_new_lines_through_a_rotation(tmp_path: Path) -> None:
    log = RotatingLog(tmp_path / "pose.log", max_bytes=10_000, backups=1)
    log.write("before")
    follower = Follower(tmp_path, "pose")
    assert list(follower.poll()) == []
    log.write("after 1")
    assert [line.text for line in follower.poll()] == ["after 1"]
    log.rotate()
    log.write("after rotation")
    assert [line.text for line in follower.poll()] == ["after rotation"]
    follower.close()
    log.close()


def test_failure_line_is_the_cause_from_the_last_run() -> None:
    earlier_run = ["[zendock] started (pid 1)", "an old error: gone", "[zendock] exited with code 1"]
    config_error = [
        "[zendock] started (pid 2)",
        "loading world",
        "python -m services.simulator: error: nope.yaml: cannot read world file: No such file",
        "[zendock] exited with code 2 (a configuration error: not restarted)",
    ]
    assert failure_line(earlier_run + config_error) == config_error[2]
    traceback = [
        "[zendock] started (pid 3)",
        "Traceback (most recent call last):",
        '  File "shared/config_errors.py"',
        "ValueError: bad pose",
        "[zendock] exited with code 1",
    ]
    assert failure_line(traceback) == "ValueError: bad pose"
    assert (
        failure_line(["[zendock] started (pid 4)", "first", "last words", "[zendock] exited with code 3"])
        == "last words"
    )
    assert failure_line(["[zendock] started (pid 5)", "[zendock] exited with code 1"]) is None


def test_run_failure_follows_a_run_as_failure_line_reads_its_last_lines() -> None:
    """Fed line by line, it gives :func:`failure_line`'s answer over the window's lines, whatever they are."""
    vocabulary = [
        "[zendock] started (pid 7)",
        "[zendock] cannot start .venv-ros2/bin/python: No such file",
        "[zendock] exited with code 1",
        "Traceback (most recent call last):",
        "error: world.yaml: cannot read",
        "ValueError: bad pose",
        "planning a path",
        "   ",
        "docked",
    ]
    rng = random.Random(57)
    for window in (1, 5, 40):
        failure = RunFailure(window_lines=window)
        kept: deque[str] = deque(maxlen=window)
        for step in range(3000):
            text = rng.choice(vocabulary)
            failure.add(text)
            kept.append(text)
            assert failure.reason() == failure_line(list(kept)), f"window {window}, line {step}: {list(kept)}"
            if rng.random() < 0.01:
                failure.clear()
                kept.clear()


def test_run_failure_forgets_an_error_once_it_leaves_the_window() -> None:
    failure = RunFailure(window_lines=200)
    failure.add("[zendock] started (pid 9)")
    failure.add("error: a transient one, long ago")
    for i in range(199):
        failure.add(f"patrolling, lap {i}")
    assert failure.reason() == "error: a transient one, long ago"
    failure.add("patrolling, lap 199")
    assert failure.reason() == "patrolling, lap 199", "the error is older than the window's lines"
    unbounded = RunFailure()
    for text in ["[zendock] started (pid 9)", "error: the first", *(f"line {i}" for i in range(1000))]:
        unbounded.add(text)
    assert unbounded.reason() == "error: the first"
