"""How well the dock is found from pixels: the simulator's camera and the perception service as processes.

A bench world (an empty 12 m x 12 m room with one dock) is written to a temporary file. The robot is
teleported to a grid of viewpoints, each facing the marker from a distance (base_link to the marker's
centre) and a viewing angle (from the marker's normal), and stands still while the camera runs. For
every frame rendered (counted by its ``camera_info``) the bench looks for the perception service's
``dock_detections`` with the same stamp and compares the dock pose with the truth (the world's dock
seen from the teleported pose). Latency is the sim clock when a detection arrives minus its image's
stamp, at real time (rtf 1): rendering, transport, decoding, detection and publishing together. The
perception service's CPU time over the frames it was sent is its cost per frame (receiving, decoding,
detecting, publishing); the simulator's own benchmark (a tool process) gives the render time per frame.
"""

from __future__ import annotations

import math
import tempfile
import threading
import time
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import psutil
import yaml

from deploy.bench.processes import ServiceGroup, free_port
from deploy.percentiles import median, percentile
from deploy.service_tools import run_tool
from shared import topics
from shared.action import spin_in_background
from shared.geometry import Pose2D
from shared.interfaces.simulator import TELEPORT, TeleportRequest
from shared.messages import CameraInfo, Clock, DockDetection
from shared.node import RELIABLE, SENSOR_DATA, Node, QoS, call_service
from shared.session import SessionSpec, open_session
from shared.world import dock_markers, load_world

#: How long the perception service remembers a marker's pose (its CONTINUITY_S; a test keeps them equal).
PERCEPTION_MEMORY_S = 0.5
RANGES_M = (0.35, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0)
ANGLES_DEG = (0.0, 15.0, 30.0, 45.0, 60.0)
BENCH_WORLD: dict[str, Any] = {
    "name": "perception_bench",
    "bounds": [-6.0, -6.0, 6.0, 6.0],
    "docks": [{"id": "home", "pose": [0.0, 0.0, 0.0]}],
    "robot": {"start": [-1.0, 0.0, 0.0]},
}


@dataclass
class Viewpoint:
    range_m: float
    angle_deg: float
    frames: int = 0
    detected: int = 0
    position_errors_m: list[float] = field(default_factory=list)
    yaw_errors_rad: list[float] = field(default_factory=list)

    def as_dict(self) -> dict[str, float]:
        rate = self.detected / self.frames if self.frames else math.nan
        return {
            "range_m": self.range_m,
            "angle_deg": self.angle_deg,
            "frames": self.frames,
            "detection_rate": round(rate, 3),
            "median_position_error_mm": _median_mm(self.position_errors_m),
            "median_yaw_error_deg": round(math.degrees(median(self.yaw_errors_rad)), 2),
        }


def _median_mm(values: list[float]) -> float:
    return round(1000.0 * median(values), 1)


class _Watcher:
    """Frames (by camera_info stamp), detections (by image stamp) and the latest sim clock."""

    def __init__(self, node: Node) -> None:
        self._lock = threading.Lock()
        self.frame_stamps: set[float] = set()
        self.detections: dict[float, DockDetection] = {}
        self.latencies_s: list[float] = []
        self._clock_s = 0.0
        node.create_subscription(CameraInfo, topics.CAMERA_INFO, self._on_info, SENSOR_DATA)
        node.create_subscription(DockDetection, topics.DOCK_DETECTIONS, self._on_detection, RELIABLE)
        node.create_subscription(Clock, topics.CLOCK, self._on_clock, QoS(depth=1))

    def _on_clock(self, msg: Clock) -> None:
        with self._lock:
            self._clock_s = max(self._clock_s, msg.clock.to_sec())

    def _on_info(self, msg: CameraInfo) -> None:
        with self._lock:
            self.frame_stamps.add(msg.header.stamp.to_sec())

    def _on_detection(self, msg: DockDetection) -> None:
        stamp = msg.header.stamp.to_sec()
        with self._lock:
            self.detections[stamp] = msg
            self.latencies_s.append(self._clock_s - stamp)

    def clock_s(self) -> float:
        with self._lock:
            return self._clock_s

    def since(self, start_s: float) -> tuple[list[float], dict[float, DockDetection]]:
        with self._lock:
            frames = sorted(s for s in self.frame_stamps if s > start_s)
            return frames, {s: d for s, d in self.detections.items() if s > start_s}


def viewpoint_pose(marker: Pose2D, range_m: float, angle_rad: float) -> Pose2D:
    """base_link ``range_m`` from the marker's centre, ``angle_rad`` off its normal, facing it."""
    heading = marker.yaw + angle_rad
    x, y = marker.x + range_m * math.cos(heading), marker.y + range_m * math.sin(heading)
    return Pose2D(x, y, math.atan2(marker.y - y, marker.x - x))


def run_perception_bench(frames_per_point: int = 12) -> dict[str, Any]:
    """Every viewpoint of the grid; returns per-point figures and a summary by range."""
    with tempfile.TemporaryDirectory(prefix="zendock-bench-perception-") as tmp:
        world_file = Path(tmp) / "perception_bench.yaml"
        world_file.write_text(yaml.safe_dump(BENCH_WORLD))
        world = load_world(world_file)
        dock = world.docks[0].pose2d
        marker = dock_markers(world)[0].pose
        endpoint, namespace = f"tcp/127.0.0.1:{free_port()}", "bench"
        points: list[Viewpoint] = []
        skipped: list[dict[str, Any]] = []
        with (
            open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))),
            ServiceGroup(
                endpoint,
                namespace,
                {
                    "simulator": ["--world", str(world_file), "-p", "rtf=1", "-p", "detection.source=aruco"],
                    "perception": ["-p", f"dock_database={world_file}"],
                },
                Path(tmp),
            ) as stack,
            open_session(SessionSpec(mode="client", connect=(endpoint,))) as session,
        ):
            node = Node("bench_perception", session, namespace)
            spin_in_background(node)
            watcher = _Watcher(node)
            deadline = time.monotonic() + 30.0
            while watcher.clock_s() == 0.0:
                if time.monotonic() > deadline:
                    raise RuntimeError(f"the simulator's clock never started:\n{stack.tails()}")
                time.sleep(0.05)
            perception = psutil.Process(stack.procs["perception"].pid)
            cpu_before = _cpu_s(perception)
            for range_m in RANGES_M:
                for angle_deg in ANGLES_DEG:
                    robot = viewpoint_pose(marker, range_m, math.radians(angle_deg))
                    reply = call_service(
                        session,
                        f"{namespace}/simulator/teleport",
                        TELEPORT,
                        TeleportRequest(robot="", x=robot.x, y=robot.y, yaw=robot.yaw),
                        timeout_s=10.0,
                    )
                    if not reply.success:  # close and far to the side the robot would stand in the dock
                        skipped.append({"range_m": range_m, "angle_deg": angle_deg, "reason": reply.message})
                        continue
                    points.append(_measure(watcher, dock, robot, range_m, angle_deg, frames_per_point, stack))
            cpu_s = _cpu_s(perception) - cpu_before
            frames_sent = len(watcher.frame_stamps)
            node.shutdown()
            node.close()
            latencies = watcher.latencies_s
        render = run_tool("services.simulator.bench", [str(world_file), "5"]).last_json()
    costs = {
        "render_ms_per_frame": round(render["render_ms_per_frame"], 2),
        "perception_cpu_ms_per_frame": round(1000.0 * cpu_s / max(1, frames_sent), 2),
    }
    return {**_report(points, latencies), **costs, "skipped": skipped}


def _cpu_s(process: psutil.Process) -> float:
    times = process.cpu_times()
    return float(times.user + times.system)


def _measure(
    watcher: _Watcher,
    dock: Pose2D,
    robot: Pose2D,
    range_m: float,
    angle_deg: float,
    frames_wanted: int,
    stack: ServiceGroup,
) -> Viewpoint:
    # Frames from before the teleport are not this viewpoint's, and the perception service's memory of the
    # marker's last pose (CONTINUITY_S) must lapse: each viewpoint is a fresh sighting, not a robot that
    # jumped, which no real one does.
    settle_s = watcher.clock_s() + PERCEPTION_MEMORY_S + 0.1
    deadline = time.monotonic() + 20.0
    while len(watcher.since(settle_s)[0]) < frames_wanted + 1:
        if time.monotonic() > deadline:
            raise RuntimeError(f"no camera frames at {range_m} m, {angle_deg} deg:\n{stack.tails()}")
        time.sleep(0.02)
    time.sleep(0.3)  # the last frames' detections still in flight
    frames, detections = watcher.since(settle_s)
    frames = frames[:frames_wanted]
    truth = dock.relative_to(robot)
    point = Viewpoint(range_m, angle_deg, frames=len(frames))
    for stamp in frames:
        found = detections.get(stamp)
        if found is None:
            continue
        point.detected += 1
        seen = found.pose.to_pose2d()
        point.position_errors_m.append(math.hypot(seen.x - truth.x, seen.y - truth.y))
        point.yaw_errors_rad.append(abs(math.remainder(seen.yaw - truth.yaw, math.tau)))
    return point


def _report(points: list[Viewpoint], latencies_s: list[float]) -> dict[str, Any]:
    by_range: dict[float, list[Viewpoint]] = defaultdict(list)
    for p in points:
        by_range[p.range_m].append(p)
    summary = {}
    for range_m, group in sorted(by_range.items()):
        frames = sum(p.frames for p in group)
        detected = sum(p.detected for p in group)
        positions = [e for p in group for e in p.position_errors_m]
        yaws = [e for p in group for e in p.yaw_errors_rad]
        summary[f"{range_m:g} m"] = {
            "detection_rate": round(detected / frames, 3) if frames else math.nan,
            "median_position_error_mm": _median_mm(positions),
            "p95_position_error_mm": round(1000.0 * percentile(positions, 0.95), 1),
            "median_yaw_error_deg": round(math.degrees(median(yaws)), 2),
        }
    frames = sum(p.frames for p in points)
    return {
        "angles_deg": list(ANGLES_DEG),
        "detection_rate": round(sum(p.detected for p in points) / frames, 3) if frames else math.nan,
        "median_latency_ms": round(1000.0 * median(latencies_s), 1),
        "by_range": summary,
        "points": [p.as_dict() for p in points],
    }


__all__ = ["run_perception_bench", "viewpoint_pose"]
