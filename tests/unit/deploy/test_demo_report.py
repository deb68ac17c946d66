"""The demo's report: missing measures read n/a, counts are integers, empty reasons are left out."""

from __future__ import annotations

import io
import json
import math

from rich.console import Console

from deploy import strict_json
from deploy.commands.demo import _print_report
from deploy.demo import DemoReport


def _report(**changes: object) -> DemoReport:
    report = DemoReport(
        docked=True,
        charging=True,
        controller="graceful",
        world="seed_room",
        dock_time_s=41.23,
        final_lateral_error_m=0.004,
        final_yaw_error_rad=0.01,
        collisions=0,
        path_length_m=3.5,
        lower_bound_s=30.0,
        wall_s=50.0,
        run_dir="runs/x",
    )
    for name, value in changes.items():
        setattr(report, name, value)
    return report


def _table(report: DemoReport) -> str:
    out = io.StringIO()
    _print_report(report.as_dict(), Console(file=out, width=120))
    return out.getvalue()


def test_counts_are_integers_and_an_empty_reason_is_left_out() -> None:
    report = _report(false_glass_cells=0.0, glass_coverage=0.8, way_width_m=0.912)
    written = json.loads(strict_json.dumps(report.as_dict()))
    assert written["false_glass_cells"] == 0 and isinstance(written["false_glass_cells"], int)
    assert "lower_bound_s_reason" not in written
    table = _table(report)
    assert "0.0" not in table.split("false glass cells")[1].splitlines()[0]
    assert "80 %" in table and "why no lower bound" not in table
    assert table.split("narrowest gap")[1].splitlines()[0].rstrip(" │").endswith("0.91 m")


def test_missing_measures_read_n_a_with_their_reason() -> None:
    report = _report(
        lower_bound_s=math.nan,
        lower_bound_s_reason="no path to the dock",
        dock_time_s=math.nan,
        final_lateral_error_m=math.nan,
        final_yaw_error_rad=math.nan,
    )
    written = json.loads(strict_json.dumps(report.as_dict()))
    assert written["false_glass_cells"] is None and written["glass_coverage"] is None
    assert written["lower_bound_s_reason"] == "no path to the dock"
    table = _table(report)
    assert "nan" not in table.lower() and "None" not in table
    for row in (
        "glass length found",
        "false glass cells",
        "lower bound",
        "dock time",
        "lateral error",
        "narrowest gap",
    ):
        assert table.split(row)[1].splitlines()[0].rstrip(" │").endswith("n/a"), row
    assert "no path to the dock" in table
