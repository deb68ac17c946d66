"""``python -m deploy.bench.ros2_dds``: what the ROS 2 DDS face (services.ros2_dds) costs, beside DDS itself.

The default stack (synthetic detector, rtf 1 by default, so sensors run at their real rates) plus ros2_dds
on a random ROS 2 domain, loopback discovery; an rclpy probe (:mod:`deploy.bench.ros2_dds_probe`, run by
``.venv-ros2/bin/python``) on the ROS 2 side, this process on zendock's. Reported:

* ``/cmd_vel`` -> ``/odom`` round trip: a rotation command until odometry shows it, through the face (rclpy ->
  face -> simulator -> face -> rclpy) and from zendock directly (this process on zendock's keys, same run);
  the simulator's step and odometry period are in both, so the face's share is the difference;
* ``/battery_status``: each message's arrival at the rclpy probe less its arrival at a zendock subscriber in
  this process (matched by header stamp): the latency the face adds;
* the same round trip and a one-way BatteryState between two rclpy processes (DDS itself, same machine);
* the face's CPU (percent of one core) and RSS, idle (no ROS 2 subscriber) and forwarding the sensor topics
  (/scan, /ultrasonic, /odom, /tf, /clock, /battery_status, /map_to_base_link_pose2d), with the rates the
  probe received.

Needs ``.venv-ros2`` (``make ros2``). Not wired into ``zendock bench ros2`` (deploy/commands is another's).
"""

from __future__ import annotations

import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import psutil
import zenoh

from deploy.launcher import Launcher, free_endpoint, load_stack
from deploy.paths import REPO_ROOT
from deploy.percentiles import median, percentile
from deploy.testing.config import DEFAULT_STACK, StackConfig
from shared.messages import BatteryState, Odometry, Twist, Vector3
from shared.node import encoding_for
from shared.session import SessionSpec, open_session

ROS2_PYTHON = REPO_ROOT / ".venv-ros2" / "bin" / "python"
PROBE = Path(__file__).with_name("ros2_dds_probe.py")


def _stats(samples: list[float]) -> dict[str, Any]:
    if not samples:
        return {"n": 0}
    return {
        "n": len(samples),
        "p50_ms": round(median(samples), 2),
        "p90_ms": round(percentile(samples, 0.9), 2),
        "max_ms": round(max(samples), 2),
    }


def _direct_round_trips(session: zenoh.Session, namespace: str, count: int) -> list[float]:
    """The probe's cmd_vel round trip from zendock's side: Twist on cmd_vel until odom shows it."""
    prefix = f"{namespace}/" if namespace else ""
    latest = [0.0, 0]
    lock = threading.Lock()

    def on_odom(sample: zenoh.Sample) -> None:
        msg = Odometry.decode(sample.payload.to_bytes())
        with lock:
            latest[0], latest[1] = msg.twist.twist.angular.z, time.time_ns()

    sub = session.declare_subscriber(f"{prefix}odom", on_odom)
    pub = session.declare_publisher(f"{prefix}cmd_vel", encoding=encoding_for(Twist.TYPE_NAME))

    def wait(predicate: Any, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with lock:
                if predicate():
                    return True
            time.sleep(0.0005)
        return False

    samples: list[float] = []
    try:
        wait(lambda: latest[1] > 0, 10.0)
        for i in range(count):
            turn = 0.5 if i % 2 == 0 else -0.5
            time.sleep(0.2)
            sent = time.time_ns()
            pub.put(Twist(Vector3(), Vector3(0.0, 0.0, turn)).encode())
            if wait(lambda t=turn, s=sent: abs(latest[0] - t) < 0.25 and latest[1] > s, 2.0):
                samples.append((latest[1] - sent) / 1e6)
            pub.put(Twist().encode())
            wait(lambda: abs(latest[0]) < 0.05, 2.0)
    finally:
        pub.undeclare()
        sub.undeclare()
    return samples


def dds_face_stack(project: Path, endpoint: str, domain: int, rtf: str, name: str) -> Launcher:
    """The default stack (synthetic detector, ``rtf``) with the ros2-dds profile on ROS 2 ``domain``, its
    router on ``endpoint`` and its project directory ``project``; not started."""
    environment = {
        **StackConfig(detector="synthetic", rtf=rtf).environment(endpoint, project),
        "ROS_DOMAIN_ID": str(domain),
    }
    stack = load_stack(DEFAULT_STACK, env=environment, project_dir=REPO_ROOT)
    return Launcher(
        stack, profiles=["ros2-dds"], project_dir=project, working_dir=REPO_ROOT, project_name=name
    )


def run(rtf: str = "1", seconds: float = 10.0, round_trips: int = 20) -> dict[str, Any]:
    if not ROS2_PYTHON.exists():
        raise RuntimeError(f"{ROS2_PYTHON} is missing: `make ros2` builds it")
    domain = random.randint(100, 200)
    with tempfile.TemporaryDirectory(prefix="zendock-bench-dds-") as tmp:
        project = Path(tmp)
        endpoint = free_endpoint()
        launcher = dds_face_stack(project, endpoint, domain, rtf, "zendock-bench")
        with launcher, open_session(SessionSpec(mode="client", connect=(endpoint,))) as session:
            launcher.wait_healthy(timeout_s=90.0)
            pid = launcher.status("ros2_dds").pid
            assert pid is not None
            face = psutil.Process(pid)
            prefix = f"{launcher.namespace}/" if launcher.namespace else ""
            zendock_arrivals: dict[int, int] = {}

            def on_battery(sample: zenoh.Sample) -> None:
                now = time.time_ns()
                stamp = BatteryState.decode(sample.payload.to_bytes()).header.stamp
                zendock_arrivals.setdefault(stamp.sec * 1_000_000_000 + stamp.nanosec, now)

            battery_sub = session.declare_subscriber(f"{prefix}battery_status", on_battery)
            direct = _direct_round_trips(session, launcher.namespace, round_trips)

            env = {k: v for k, v in os.environ.items() if not k.startswith(("VIRTUAL_ENV", "PYTHON"))}
            env.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
            probe = subprocess.Popen(
                [str(ROS2_PYTHON), str(PROBE), "--seconds", str(seconds), "--round-trips", str(round_trips)],
                stdout=subprocess.PIPE,
                text=True,
                cwd=REPO_ROOT,
                env=env,
            )
            phases: dict[str, dict[str, Any]] = {}
            marks: dict[str, tuple[float, float, int]] = {}  # phase -> (wall, cpu seconds, rss) at its start
            assert probe.stdout is not None
            for line in probe.stdout:
                event = json.loads(line)
                cpu = face.cpu_times()
                marks[event["phase"]] = (time.monotonic(), cpu.user + cpu.system, face.memory_info().rss)
                phases[event["phase"]] = event
            probe.wait(timeout=30)
            battery_sub.undeclare()

    def cpu_between(start: str, end: str) -> dict[str, float]:
        (t0, c0, _), (t1, c1, rss) = marks[start], marks[end]
        return {"cpu_percent": round(100.0 * (c1 - c0) / (t1 - t0), 1), "rss_mb": round(rss / 2**20, 1)}

    added = [
        (ros - zendock_arrivals[stamp]) / 1e6
        for stamp, ros in phases["battery"]["arrivals"]
        if stamp in zendock_arrivals
    ]
    dds_one_way = [(arrival - stamp) / 1e6 for stamp, arrival in phases["dds_battery"]["arrivals"]]
    return {
        "rtf": rtf,
        "cmd_vel_odom_round_trip": {
            "through_face": _stats(phases["cmd_vel"]["round_trips_ms"]),
            "zendock_direct": _stats(direct),
            "rclpy_to_rclpy": _stats(phases["dds_round_trip"]["round_trips_ms"]),
        },
        "battery_status_latency": {
            "added_by_face": _stats(added),
            "rclpy_to_rclpy_one_way": _stats(dds_one_way),
        },
        "face": {
            "idle": cpu_between("idle", "idle_end"),
            "forwarding_sensors": cpu_between("sensors", "sensors_end"),
            "rates_hz": phases["sensors_end"]["rates_hz"],
        },
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m deploy.bench.ros2_dds", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "--rtf", default="1", help="the simulator's real-time factor (default 1: real sensor rates)"
    )
    parser.add_argument("--seconds", type=float, default=10.0, help="length of each measuring phase")
    parser.add_argument("--round-trips", type=int, default=20)
    args = parser.parse_args(argv)
    try:
        report = run(args.rtf, args.seconds, args.round_trips)
    except RuntimeError as exc:
        print(f"{parser.prog}: {exc}", file=sys.stderr)
        return 1
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
