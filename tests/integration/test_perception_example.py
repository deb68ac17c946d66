"""The perception example, written from the contract pages alone (eclipse-zenoh, msgpack, numpy, OpenCV and
PyYAML): it passes ``zendock conform perception`` and docks in a small campaign in its place."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from deploy.contracts.conform import ConformOptions, run_conform
from deploy.paths import REPO_ROOT

EXAMPLE = REPO_ROOT / "examples" / "perception" / "perception.py"


def test_the_perception_example_conforms(tmp_path: Path) -> None:
    report = run_conform("perception", ["python", str(EXAMPLE)], ConformOptions(runs_dir=tmp_path))
    rows = "\n".join(f"{c.result} {c.name}: {c.evidence}" for c in report.checks)
    assert report.passed, rows
    assert "sees the dock from 0.4 to 3 m and 40 degrees aside" in rows


def test_the_perception_example_docks_in_a_small_campaign(tmp_path: Path) -> None:
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "deploy.cli",
            "trials",
            "--world",
            "seed_room",
            "--n",
            "2",
            "--workers",
            "1",
            "--seed",
            "3",
            "--detector",
            "aruco",
            "--service",
            f"perception=python {EXAMPLE}",
            "--runs-dir",
            str(tmp_path),
            "--json",
        ],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    summary = json.loads(run.stdout)
    assert summary["successes"] == 2 and summary["collisions"] == 0, summary
    assert summary["median_lateral_error_m"] < 0.02, summary
