"""The plugin's wiring without a stack: options refused early, markers checked before anything starts, a
failed test's report carrying the services' log tails, the unhealthy stack's one line."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pytest

from deploy.launcher import load_stack
from deploy.launcher.logs import RotatingLog
from deploy.launcher.status import ServiceStatus
from deploy.replacements import Replacement, apply_replacements
from deploy.testing.config import DEFAULT_STACK
from deploy.testing.plugin import attach_logs
from deploy.testing.stack import run_replacements_in, unhealthy_line

pytest_plugins = ["pytester"]


def _write_log(logs_dir: Path, service: str, lines: list[str]) -> None:
    log = RotatingLog(logs_dir / f"{service}.log")
    for line in lines:
        log.write(line)
    log.close()


@dataclass
class FakeReport:
    sections: list[tuple[str, str]] = field(default_factory=list)


def test_a_report_gets_each_services_log_tail(tmp_path: Path) -> None:
    _write_log(tmp_path, "docking", [f"line {i}" for i in range(100)])
    _write_log(tmp_path, "pose", ["[zendock] started (pid 12)", "pose ready"])
    report = FakeReport()
    assert attach_logs(report, tmp_path, ["docking", "pose", "planner"], lines=5) == 2
    titles = [title for title, _ in report.sections]
    assert titles == ["zendock log: docking (last 5 lines)", "zendock log: pose (last 2 lines)"]
    assert report.sections[0][1].splitlines() == [f"line {i}" for i in range(95, 100)]


def _status(
    name: str, state: str, restarts: int = 0, health: str = "starting", detail: str = ""
) -> ServiceStatus:
    return ServiceStatus(name, state, pid=None, restarts=restarts, health=health, phase=state, detail=detail)


def test_an_unhealthy_stack_is_one_line_naming_the_service_that_failed(tmp_path: Path) -> None:
    _write_log(
        tmp_path,
        "docking",
        [
            "[zendock] started (pid 3)",
            "Traceback (most recent call last):",
            '  File "x.py", line 1',
            "ModuleNotFoundError: No module named 'mine'",
        ],
    )
    statuses = [
        _status("router", "running", health="none"),
        _status("planner", "stopped", detail="waiting for map"),
        _status("docking", "restarting", restarts=2),
    ]
    line = unhealthy_line(statuses, tmp_path, 20.0)
    assert "\n" not in line
    assert line.startswith(
        "zendock stack not healthy within 20 s: docking is restarting (health starting, restarts 2)"
    )
    assert line.endswith("its log: ModuleNotFoundError: No module named 'mine'")
    waiting = unhealthy_line(statuses[:2], tmp_path, 20.0)
    assert (
        "planner is stopped" in waiting and "waiting for map" in waiting and "it printed nothing" in waiting
    )


def test_a_replaced_service_runs_in_the_pytest_rootdir(tmp_path: Path) -> None:
    stack = load_stack(DEFAULT_STACK, env={}, project_dir=tmp_path)
    replaced = apply_replacements(stack, [Replacement.of("docking", "python my_docking.py")])
    moved = run_replacements_in(stack, replaced, tmp_path)
    assert moved.services["docking"].working_dir == str(tmp_path)
    assert moved.services["docking"].command[:2] == ["python", "my_docking.py"]
    assert "-p" in moved.services["docking"].command  # zendock's flags follow the replacement's words
    assert all(spec.working_dir is None for name, spec in moved.services.items() if name != "docking")


def test_a_mistyped_option_stops_the_run_before_any_test(pytester: pytest.Pytester) -> None:
    pytester.makepyfile("def test_nothing():\n    pass\n")
    result = pytester.runpytest("--zendock-service", "dockin=python x.py")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*no replaceable service 'dockin'*"])
    result = pytester.runpytest("--zendock-rtf", "-1")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*rtf='-1': expected a positive number or 'max'*"])


def test_a_wrong_marker_fails_the_test_in_one_line_without_a_stack(pytester: pytest.Pytester) -> None:
    pytester.makepyfile("""
        import pytest

        @pytest.mark.zendock(world="nowhere")
        def test_uses_a_stack(zendock_stack):
            pass
    """)
    result = pytester.runpytest()
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines(["*zendock stack: world='nowhere': no shipped world of that name*"])
    result.stdout.no_fnmatch_line("*zendock log:*")


def test_a_failed_test_with_a_stack_shows_the_log_tails(pytester: pytest.Pytester, tmp_path: Path) -> None:
    """The hook itself: a stand-in stack (its logs directory and services) in the item's stash."""
    logs = tmp_path / "logs"
    _write_log(logs, "docking", ["docking: approaching", "docking: lost the dock"])
    pytester.makeconftest(f"""
        import pytest
        from deploy.testing.plugin import STACK_KEY

        class Stand:
            logs_dir = __import__("pathlib").Path({str(logs)!r})
            services = ["docking"]

        @pytest.fixture
        def stand(request):
            request.node.stash[STACK_KEY] = Stand()
    """)
    pytester.makepyfile("""
        def test_fails(stand):
            assert False, "did not dock"

        def test_passes(stand):
            pass
    """)
    result = pytester.runpytest()
    result.assert_outcomes(failed=1, passed=1)
    result.stdout.fnmatch_lines(["*zendock log: docking (last 2 lines)*", "*docking: lost the dock*"])
    assert result.stdout.str().count("zendock log: docking") == 1
