"""How much faster than real time the simulator's pure core runs, without a bus.

One simulated second is what the simulator service computes per second of robot time: 100 physics
steps with odometry, 10 lidar scans, 20 ultrasonic readings, 10 synthetic dock detections, 50 contact
checks and, while someone watches the camera, 15 rendered 640x480 frames. The robot wanders (a slow
sine-wave steering command) so contacts, sensor geometry and the rendered view vary. Both real-time
factors are reported: with the camera (someone subscribes to camera/image_raw) and without it.

A fleet world (one that lists its robots) puts all of them in one room, stepped together, each with every
sensor, as the simulator service serves a fleet; the camera renders for the first robot only.

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
from services.simulator.physics import Robot, SimParams, step_together
from shared.geometry import Pose2D
from shared.world import World, load_world

LIDAR_HZ = 10
ULTRASONIC_HZ = 20
DETECTION_HZ = 10
CONTACT_HZ = 50


def bench_simulation(
    world_path: str | Path, seconds: float, params: SimParams | None = None
) -> dict[str, float]:
    """Run ``seconds`` of simulated time as fast as possible; returns timings and the real-time factor."""
    world = load_world(world_path)
    robots = _robots(world, params)
    sim = robots[0]
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
        step_together(robots, [(0.4, 1.2 * math.sin(0.5 * t + k)) for k in range(len(robots))])
        for robot in robots:
            _ = robot.odom_pose, robot.twist, robot.map_to_odom()
            robot.drain_collisions()
        spent["step"] += clock() - t0
        calls["step"] += 1
        for robot in robots:
            for name, call in (
                ("lidar", robot.lidar_scan),
                ("ultrasonic", robot.ultrasonic_range),
                ("detection", robot.detect_docks),
                ("contact", robot.dock_contact),
            ):
                if i % every[name] == 0:
                    t0 = clock()
                    call()
                    spent[name] += clock() - t0
                    calls[name] += 1
        if i % every["render"] == 0:
            t0 = clock()
            renderer.render(
                sim.pose, Motion(sim.twist.linear_mps, sim.twist.angular_radps), sim.other_footprints()
            )
            spent["render"] += clock() - t0
            calls["render"] += 1
    wall_s = clock() - started
    sim_s = steps * dt
    result: dict[str, float] = {
        "sim_seconds": sim_s,
        "wall_seconds": wall_s,
        "real_time_factor": sim_s / (wall_s - spent["render"]),
        "real_time_factor_with_camera": sim_s / wall_s,
        "render_ms_per_frame": 1e3 * spent["render"] / max(1, calls["render"]),
        "steps_per_s": steps / wall_s,
        "robots": float(len(robots)),
        "ms_per_sim_s_without_camera": 1e3 * (wall_s - spent["render"]) / sim_s,
        "collisions": float(sum(sum(r.collision_counts.values()) for r in robots)),
    }
    for name in spent:
        if name == "render":
            continue
        result[f"{name}_us_per_call"] = 1e6 * spent[name] / max(1, calls[name])
    return result


def _robots(world: World, params: SimParams | None) -> list[Robot]:
    """The world's fleet in one room, or its one robot."""
    if not world.robots:
        return [Robot(world, params=params)]
    first, *rest = world.robots
    room = Robot(world, params=params, start=Pose2D.from_seq(first.start), name=first.name)
    return [room] + [room.join(r.name, Pose2D.from_seq(r.start), params) for r in rest]


def main(world_path: str, seconds: float) -> int:
    print(json.dumps(bench_simulation(world_path, seconds)))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("world", help="world file, e.g. deploy/worlds/seed_room.yaml")
    parser.add_argument("seconds", type=float, nargs="?", default=60.0, help="simulated seconds (default 60)")
    args = parser.parse_args()
    raise SystemExit(main(args.world, args.seconds))
