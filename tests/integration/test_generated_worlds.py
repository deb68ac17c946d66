"""Generated rooms end to end: ``zendock worlds generate`` writes reachable rooms, and a small campaign over
fresh glass rooms docks in each, every room named by its seed."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from deploy.observer import ARRIVAL_SPEED_LIMIT_MPS
from deploy.paths import REPO_ROOT
from shared.world import load_world


def _zendock(*args: str, timeout_s: float = 300.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "deploy.cli", *args],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=timeout_s,
    )


def test_worlds_generate_writes_one_room_a_seed(tmp_path: Path) -> None:
    done = _zendock(
        "worlds", "generate", "--kind", "glass", "--seed", "5", "--count", "2", "--out", str(tmp_path)
    )
    assert done.returncode == 0, done.stderr
    paths = [Path(line) for line in done.stdout.split()]
    assert [load_world(p).name.split("-")[2] for p in paths] == ["5", "6"]
    again = _zendock("worlds", "generate", "--kind", "glass", "--seed", "5", "--out", str(tmp_path / "again"))
    assert Path(again.stdout.strip()).read_text() == paths[0].read_text()  # the seed names the room


def test_a_campaign_over_fresh_glass_rooms_docks_in_each(tmp_path: Path) -> None:
    """Two fresh glass rooms at 8x: each docks, and meets its plate no faster than at 1x (the world waits
    for the command of each control tick, so the speed-up changes nothing the robot does)."""
    done = _zendock(
        "trials",
        "--rtf",
        "8",
        "--world",
        "generated:glass",
        "--n",
        "2",
        "--seed",
        "1",
        "--workers",
        "1",
        "--detector",
        "synthetic",
        "--runs-dir",
        str(tmp_path),
        "--json",
    )
    assert done.returncode == 0, done.stderr[-3000:]
    summary = json.loads(done.stdout)
    assert summary["n"] == 2 and summary["successes"] == 2 and summary["collisions"] == 0, summary
    assert set(summary["worlds"]) == {"generated-glass-1", "generated-glass-2-2"}, summary["worlds"]
    assert all(w["n"] == 1 for w in summary["worlds"].values())
    assert summary["max_arrival_speed_mps"] <= ARRIVAL_SPEED_LIMIT_MPS, summary
    # Each trial says how wide its way to the dock is at its narrowest (a robot is 0.3 m wide).
    trials = [json.loads(p.read_text())["trials"][0] for p in sorted(tmp_path.glob("trials-*/trials.json"))]
    assert len(trials) == 2 and all(0.3 < t["way_width_m"] <= 3.0 for t in trials), trials
