"""``zendock fleet`` end to end: two robots with real planners meet head-on in a corridor one robot wide.

Each patrols to the far room and back, so they meet inside the corridor; the traffic rule sends the one
without priority back to a passing place while the other waits, and both get through. The run's JSON
report (last line) must say so: give-ways that ended, distance driven, no collision.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

from tests.support.processes import REPO_ROOT

CORRIDOR = REPO_ROOT / "deploy/worlds/fleet/corridor_meeting.yaml"


def _fleet(*args: str, timeout_s: float = 240.0) -> subprocess.CompletedProcess[str]:
    """``zendock fleet``; however the test ends, the command is stopped with SIGTERM (it brings its stack
    down, as on Ctrl-C) rather than killed, which would leave its services running."""
    argv = [sys.executable, "-m", "deploy.cli", "fleet", *args]
    proc = subprocess.Popen(argv, cwd=REPO_ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        out, err = proc.communicate(timeout=timeout_s)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.communicate(timeout=30.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.communicate()
    return subprocess.CompletedProcess(argv, proc.returncode, out, err)


def _tail(log: Path, lines: int = 40) -> str:
    """The last lines of a service's log in a run directory, to show why a robot did what it did."""
    return (
        f"{log.name}:\n" + "\n".join(log.read_text().splitlines()[-lines:]) if log.is_file() else f"no {log}"
    )


def test_two_robots_meeting_head_on_in_a_corridor_both_get_through(tmp_path: Path) -> None:
    done = _fleet(
        "--world",
        str(CORRIDOR),
        "--duration",
        "70",
        "--rtf",
        "4",
        "--seed",
        "3",
        "--runs-dir",
        str(tmp_path),
        "--json",
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    report = json.loads(done.stdout.splitlines()[-1])
    assert {"robots", "collisions", "reservation_conflicts", "sim_s", "wall_s"} <= set(report)
    robots = {r["name"]: r for r in report["robots"]}
    assert set(robots) == {"r1", "r2"}
    assert report["collisions"] == {"total": 0, "robot_robot": 0, "robot_world": 0}
    assert report["give_ways"] >= 1 and report["max_give_way_s"] < 60.0, report
    run_dir = next(tmp_path.glob("fleet-*"))
    # Through the corridor and on to the far room (7 m from start to the far waypoint) at least once each.
    short = [name for name, r in robots.items() if r["distance_m"] <= 9.0]
    assert not short, (robots, *(_tail(run_dir / f"docking_{name}.log") for name in short))
    assert (run_dir / "fleet.png").is_file() and (run_dir / "fleet.json").is_file()
    logs = (run_dir / "docking_r1.log").read_text() + (run_dir / "docking_r2.log").read_text()
    assert "met r" in logs and "gave way" in logs
    assert "no path from" not in logs, "a planner gave up on the corridor"


def test_bad_arguments_get_one_clear_message(tmp_path: Path) -> None:
    missing = _fleet("--world", str(tmp_path / "nope.yaml"), timeout_s=60.0)
    assert missing.returncode == 2 and "no such file" in missing.stderr, missing.stderr
    no_docks = tmp_path / "no_docks.yaml"
    no_docks.write_text("name: bare\nbounds: [0, 0, 5, 5]\nrobot: {start: [2, 2, 0]}\n")
    bare = _fleet("--world", str(no_docks), "--runs-dir", str(tmp_path), timeout_s=60.0)
    assert bare.returncode == 2 and "needs docks" in bare.stderr and "Traceback" not in bare.stderr, (
        bare.stderr
    )
    assert bare.stderr.count(str(no_docks)) == 1, "the file named once"
    bad = _fleet("--duration", "-5", timeout_s=60.0)
    assert bad.returncode == 2 and "--duration" in bad.stderr
