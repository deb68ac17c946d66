"""Which of a marker's two mirror poses zendock's perception believes, over rendered frames.

The simulator's camera renders a dock seen from 36 viewpoints (0.4 to 3.5 m from the marker, 15 to 40
degrees aside), 6 noise seeds each; for every frame the perception's fits are chosen by residual alone and
with the dock database's heading (0.05 rad off, as a localiser leaves it) among fits up to ``ratio`` times
the best. Prints how many frames end with the wrong (mirror) heading. Run from the repository:
``python tools/perception_mirror_probe.py`` (measurement 84).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from services.perception.markers import (
    MAX_TILT_RAD,
    MarkerFinder,
    choose_fit,
    facing_seed,
    marker_poses,
    refine_upright,
    upright_marker,
)
from services.simulator.camera import CameraParams, CameraRenderer, build_scene
from shared.geometry import Pose2D
from shared.world import DOCK_GEOMETRY, dock_markers
from tests.unit.perception.test_markers import _base_from_optical, _world

RANGES_M = (0.4, 1.0, 2.0, 2.5, 3.0, 3.5)
ANGLES_DEG = (-40, -30, -15, 15, 30, 40)


def main() -> None:
    world, params = _world(), CameraParams()
    marker = dock_markers(world)[0]
    base_from_optical = _base_from_optical(params)
    finder = MarkerFinder(world.aruco_dictionary)
    face = DOCK_GEOMETRY.marker_pose(world.docks[0])
    K = params.intrinsics()
    for label, ratio, with_heading in (
        ("residual alone", 2.0, False),
        *((f"database heading, ratio {r:g}", r, True) for r in (2.0, 4.0, 8.0)),
    ):
        right = wrong = 0
        for range_m in RANGES_M:
            for angle_deg in ANGLES_DEG:
                a = math.radians(angle_deg)
                x, y = face.x + range_m * math.cos(face.yaw + a), face.y + range_m * math.sin(face.yaw + a)
                robot = Pose2D(x, y, math.atan2(face.y - y, face.x - x))
                truth = face.relative_to(robot)
                prior = Pose2D(truth.x, truth.y, truth.yaw + 0.05) if with_heading else None
                for seed in range(6):
                    image = CameraRenderer(build_scene(world), params, np.random.default_rng(seed)).render(
                        robot
                    )
                    sightings = finder.find(image)
                    if not sightings:
                        continue
                    observed = cv2.undistortPoints(sightings[0].corners.reshape(-1, 1, 2), K, np.zeros(5))
                    observed = observed.reshape(-1, 2)
                    poses = [
                        p
                        for p in marker_poses(sightings[0], marker.size_m, K, np.zeros(5), base_from_optical)
                        if p.tilt_rad <= MAX_TILT_RAD
                    ]
                    seeds = [upright_marker(p) for p in poses] + [
                        facing_seed(observed, marker.size_m, base_from_optical)
                    ]
                    fits = [
                        refine_upright(s, observed, marker.size_m, marker.centre_height_m, base_from_optical)[
                            ::-1
                        ]
                        for s in seeds
                    ]
                    _residual, fitted = choose_fit(fits, prior, ratio)
                    if abs(math.remainder(fitted.yaw - truth.yaw, math.tau)) < 0.15:
                        right += 1
                    else:
                        wrong += 1
        print(f"{label}: {wrong} of {right + wrong} frames took the mirror")


if __name__ == "__main__":
    main()
