"""How much faster than real time the simulator's pure core runs, without a bus.

One simulated second is what the simulator service computes per second of robot time: 100 physics
steps with odometry, 10 lidar scans, 20 ultrasonic readings, 10 synthetic dock detections, 50 contact
checks and, while someone watches the camera, 15 rendered 640x480 frames. The robot wanders (a slow
sine-wave steering command) so contacts, sensor geometry and the rendered view vary. Both real-time
factors are reported: with the camera (someone subscribes to camera/image_raw) and without it.

    python -m services.simulator.bench deploy/worlds/seed_room.yaml 60
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from services.simulator.camera import CameraParams, CameraRenderer, Motion, build_scene
from services.simulator.physics import SimParams, SimWorld
from shared.world import load_world

LIDAR_HZ = 10
ULTRASONIC_HZ = 20
DETECTION_HZ = 10
CONTACT_HZ = 50


def bench_simulation(
    world_path: str | Path, seconds: float, params: SimParams | None = None
) -> dict[str, float]:
    """Run ``seconds`` of simulated time as fast as possible; returns timings and the real-time factor."""
    world = load_world(world_path)
    sim = SimWorld(world, params=params)
    camera_params = CameraParams()
    renderer = CameraRenderer(build_scene(world), camera_params, np.random.default_rng(0))
    dt = sim.params.dt_s
    steps = max(1, round(seconds / dt))
    every = {
        name: max(1, round(1.0 / (hz * dt)))
        for name, hz in (
            ("lidar", LIDAR_HZ),
            ("ultrasonic", ULTRASONIC_HZ),
            ("detection", DETECTION_HZ),
            ("contact", CONTACT_HZ),
            ("render", camera_params.rate_hz),
        )
    }
    spent = {"step": 0.0, "lidar": 0.0, "ultrasonic": 0.0, "detection": 0.0, "contact": 0.0, "render": 0.0}
    calls = dict.fromkeys(spent, 0)
    clock = time.perf_counter
    started = clock()
    for i in range(steps):
        t = i * dt
        t0 = clock()
        sim.step(0.4, 1.2 * math.sin(0.5 * t))
        _ = sim.odom_pose, sim.twist, sim.map_to_odom()
        sim.drain_collisions()
        spent["step"] += clock() - t0
        calls["step"] += 1
        for name, call in (
            ("lidar", sim.lidar_scan),
            ("ultrasonic", sim.ultrasonic_range),
            ("detection", sim.detect_docks),
            ("contact", sim.dock_contact),
            ("render", lambda: renderer.render(sim.pose, Motion(sim.twist.linear_mps, sim.twist.angular_radps))),
        ):
            if i % every[name] == 0:
                t0 = clock()
                call()
                spent[name] += clock() - t0
                calls[name] += 1
    wall_s = clock() - started
    sim_s = steps * dt
    result: dict[str, float] = {
        "sim_seconds": sim_s,
        "wall_seconds": wall_s,
        "real_time_factor": sim_s / (wall_s - spent["render"]),
        "real_time_factor_with_camera": sim_s / wall_s,
        "render_ms_per_frame": 1e3 * spent["render"] / max(1, calls["render"]),
        "steps_per_s": steps / wall_s,
        "collisions": float(sum(sim.collision_counts.values())),
    }
    for name in spent:
        if name == "render":
            continue
        result[f"{name}_us_per_call"] = 1e6 * spent[name] / max(1, calls[name])
    return result


def main(world_path: str, seconds: float) -> int:
    print(json.dumps(bench_simulation(world_path, seconds)))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("world", help="world file, e.g. deploy/worlds/seed_room.yaml")
    parser.add_argument("seconds", type=float, nargs="?", default=60.0, help="simulated seconds (default 60)")
    args = parser.parse_args()
    raise SystemExit(main(args.world, args.seconds))
