"""``zendock bench nav2``: from ``up`` to a Nav2 script's ``waitUntilNav2Active()`` returning, and what the
ROS 2 DDS face costs.

Each repeat starts the default stack with the ``ros2-dds`` profile on a free port and a fresh ROS 2
domain (discovery on loopback), waits for it to be healthy, then runs the rclpy user
(``tests/support/ros2_user.py``, in ``.venv-ros2``) for its ``nav2_active`` step: the protocol
``waitUntilNav2Active()`` speaks (``amcl/get_state``, a zero ``/initialpose`` until ``/amcl_pose``,
``bt_navigator/get_state``). Reported per repeat: the seconds to healthy, the protocol's own seconds
and the total from ``up``; then the face's CPU (share of one core) and RSS (its process and children)
while idle, and while a ROS 2 user echoes the battery and the clock and drives on ``/cmd_vel`` (Twist);
then its RSS once a user has driven the robot with TwistStamped, which the face's node takes by swapping the
type it holds /cmd_vel under (before measurement 134, on a second DDS participant). (Before 3 December 2026
the busy figures included the TwistStamped drive.)
"""

from __future__ import annotations

import json
import os
import random
import statistics
import subprocess
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import psutil

from deploy.bench.ros2_dds import dds_face_stack
from deploy.launcher import Launcher, free_endpoint
from deploy.paths import REPO_ROOT

ROS2_PYTHON = REPO_ROOT / ".venv-ros2" / "bin" / "python"
USER_SCRIPT = REPO_ROOT / "tests" / "support" / "ros2_user.py"
#: What the busy user does while the face's CPU is measured: /cmd_vel as Twist, Jazzy's default.
BUSY_STEPS = "battery,clock,drive"
#: Then /cmd_vel as TwistStamped, which the face takes by swapping its subscription's type.
STAMPED_STEPS = "drive_stamped"


class BenchError(RuntimeError):
    """The bench cannot run here (no .venv-ros2) or a run went wrong; the message says which."""


@dataclass(frozen=True)
class Nav2Run:
    healthy_s: float
    protocol_s: float
    up_to_active_s: float
    face_cpu_idle: float
    face_cpu_busy: float
    face_rss_idle_mb: float
    face_rss_busy_mb: float
    face_rss_stamped_mb: float


def _user_env(domain: int) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("VIRTUAL_ENV", "PYTHON"))}
    env.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    env.pop("ROS_LOCALHOST_ONLY", None)
    return env


def _face_processes(launcher: Launcher) -> list[psutil.Process]:
    status = launcher.status("ros2_dds")
    if status.pid is None:
        raise BenchError(f"ros2_dds is not running ({status.state}: {status.detail})")
    face = psutil.Process(status.pid)
    return [face, *face.children(recursive=True)]


def _cpu_share(processes: list[psutil.Process], seconds: float) -> float:
    def cpu() -> float:
        return sum(p.cpu_times().user + p.cpu_times().system for p in processes)

    before = cpu()
    time.sleep(seconds)
    return (cpu() - before) / seconds


def _rss_mb(processes: list[psutil.Process]) -> float:
    return sum(p.memory_info().rss for p in processes) / 1e6


def _user_steps(domain: int, steps: str) -> tuple[list[dict[str, Any]], str]:
    """Run the rclpy user's ``steps`` to the end: the steps' reports, and the end of its stderr."""
    done = subprocess.run(
        [str(ROS2_PYTHON), str(USER_SCRIPT), "--steps", steps],
        cwd=REPO_ROOT,
        env=_user_env(domain),
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    reports = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    return reports, done.stderr[-1500:]


def _protocol_seconds(domain: int) -> float:
    reports, stderr = _user_steps(domain, "nav2_active")
    for step in reports:
        if step.get("step") == "nav2_active":
            if not step["ok"]:
                raise BenchError(f"waitUntilNav2Active's protocol failed: {json.dumps(step)}")
            return float(step["seconds"])
    raise BenchError(f"the rclpy user reported nothing: {stderr}")


def _busy(domain: int, steps: str, seconds: float, face: list[psutil.Process]) -> tuple[float, float]:
    """The face's CPU share and RSS while an rclpy user runs ``steps``."""
    user = subprocess.Popen(
        [str(ROS2_PYTHON), str(USER_SCRIPT), "--steps", steps],
        cwd=REPO_ROOT,
        env=_user_env(domain),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        return _cpu_share(face, seconds), _rss_mb(face)
    finally:
        user.kill()
        user.wait(timeout=10)


def _after_stamped(domain: int, face: list[psutil.Process]) -> float:
    """The face's RSS once an rclpy user has driven the robot with TwistStamped (through the face's second
    participant: the robot moved, or the bench says it did not)."""
    reports, stderr = _user_steps(domain, STAMPED_STEPS)
    if not any(step.get("step") == "cmd_vel_stamped_odom" and step.get("ok") for step in reports):
        raise BenchError(
            f"driving with TwistStamped through the face did not move the robot: {reports or stderr}"
        )
    return _rss_mb(face)


def one_run(idle_s: float, busy_s: float) -> Nav2Run:
    domain = random.randint(100, 200)
    with tempfile.TemporaryDirectory(prefix="zendock-bench-nav2-") as tmp:
        launcher = dds_face_stack(Path(tmp), free_endpoint(), domain, "4", "bench-nav2")
        started = time.monotonic()
        try:
            launcher.up()
            launcher.wait_healthy(timeout_s=90.0)
            healthy_s = time.monotonic() - started
            protocol_s = _protocol_seconds(domain)
            up_to_active_s = time.monotonic() - started
            face = _face_processes(launcher)
            idle = _cpu_share(face, idle_s)
            rss_idle = _rss_mb(face)
            busy, rss_busy = _busy(domain, BUSY_STEPS, busy_s, face)
            rss_stamped = _after_stamped(domain, face)
        except psutil.NoSuchProcess as exc:
            last = launcher.logs("ros2_dds", tail_lines=5)
            raise BenchError(
                f"ros2_dds (pid {exc.pid}) exited while it was measured; its last lines:\n" + "\n".join(last)
            ) from None
        finally:
            launcher.down()
    return Nav2Run(
        round(healthy_s, 2),
        round(protocol_s, 2),
        round(up_to_active_s, 2),
        round(idle, 4),
        round(busy, 4),
        round(rss_idle, 1),
        round(rss_busy, 1),
        round(rss_stamped, 1),
    )


def run_bench(repeats: int, idle_s: float = 10.0, busy_s: float = 8.0) -> dict[str, Any]:
    """``repeats`` runs and the median of each figure."""
    if not ROS2_PYTHON.exists():
        raise BenchError(f"{ROS2_PYTHON} is missing: run make ros2")
    runs = [one_run(idle_s, busy_s) for _ in range(repeats)]
    rows = [asdict(r) for r in runs]
    return {"runs": rows, "median": {key: statistics.median(row[key] for row in rows) for key in rows[0]}}
