"""``zendock nav`` argument handling and ``zendock bench planner`` output (no stack needed)."""

from __future__ import annotations

import json

import pytest

from deploy.cli import main


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["nav", "nan", "1", "0"], "finite"),
        (["nav", "1", "2", "inf"], "finite"),
        (["nav", "1", "2", "0", "--timeout", "0"], "--timeout"),
        (["nav", "1", "2", "0", "--namespace", "bad ns"], "--namespace"),
    ],
)
def test_nav_refuses_bad_arguments_before_touching_the_bus(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_nav_without_a_router_fails_with_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["nav", "1", "2", "0", "--connect", "tcp/127.0.0.1:1"]) == 1
    err = capsys.readouterr().err
    assert "cannot reach a Zenoh router at tcp/127.0.0.1:1" in err and err.count("\n") == 1


def test_bench_planner_reports_planning_stages_as_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(["bench", "planner", "--planning-only", "--repeats", "1", "--resolution", "0.1", "--json"]) == 0
    )
    result = json.loads(capsys.readouterr().out)
    assert (result["grid_width"], result["grid_height"]) == (200.0, 200.0)
    assert {
        "plan_ms",
        "astar_ms",
        "plan_full_resolution_ms",
        "inflation_ms",
        "path_length_m",
    } <= result.keys()
    assert all(result[k] > 0 for k in ("plan_ms", "astar_ms", "path_length_m"))
