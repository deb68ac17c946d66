"""The simulator's nested parameters keep the defaults its flat parameters had (74d55a3's
``services/simulator/node.py``), so the regrouping changed no behaviour: old name, new dotted name, value."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from services.simulator.params import Params

SEED_ROOM = str(Path(__file__).resolve().parents[3] / "deploy" / "worlds" / "seed_room.yaml")

FLAT_DEFAULTS = [
    ("clock_rate_hz", "clock.rate_hz", 20.0),
    ("odom_rate_hz", "odom.rate_hz", 20.0),
    ("tf_rate_hz", "tf.rate_hz", 20.0),
    ("tf_static_rate_hz", "tf.static_rate_hz", 1.0),
    ("scan_rate_hz", "lidar.rate_hz", 10.0),
    ("ultrasonic_rate_hz", "ultrasonic.rate_hz", 20.0),
    ("detection_rate_hz", "detection.rate_hz", 15.0),
    ("contact_rate_hz", "contact.rate_hz", 20.0),
    ("ir_rate_hz", "ir.rate_hz", 20.0),
    ("ground_truth_rate_hz", "ground_truth.rate_hz", 20.0),
    ("cmd_vel_timeout_s", "drive.cmd_vel_timeout_s", 0.3),
    ("pace_to_drivers", "pacing.to_drivers", True),
    ("driver_gap_s", "pacing.driver_gap_s", 0.15),
    ("driver_wait_max_s", "pacing.driver_wait_max_s", 0.1),
    ("pace_to_pose", "pacing.to_pose", True),
    ("pose_gap_s", "pacing.pose_gap_s", 0.3),
    ("wheel_separation_m", "drive.wheel_separation_m", 0.26),
    ("wheel_radius_m", "drive.wheel_radius_m", 0.033),
    ("max_linear_mps", "drive.max_linear_mps", 0.5),
    ("max_angular_radps", "drive.max_angular_radps", 1.5),
    ("max_linear_accel", "drive.max_linear_accel", 1.0),
    ("max_angular_accel", "drive.max_angular_accel", 3.0),
    ("max_linear_decel", "drive.max_linear_decel", 2.5),
    ("max_angular_decel", "drive.max_angular_decel", 6.0),
    ("lidar_noise_m", "lidar.noise_m", 0.01),
    ("ultrasonic_noise_m", "ultrasonic.noise_m", 0.005),
    ("ultrasonic_fov_rad", "ultrasonic.field_of_view_rad", 0.5),
    ("ultrasonic_max_range_m", "ultrasonic.range_max_m", 3.0),
    ("dock_detector", "detection.source", "synthetic"),
    ("detection_latency_s", "detection.latency_s", 0.05),
    ("detection_position_noise_m", "detection.position_sigma_m", 0.003),
    ("detection_yaw_noise_rad", "detection.yaw_sigma_rad", 0.01),
    ("detection_fov_rad", "detection.horizontal_fov_rad", 1.2),
    ("detection_range_m", "detection.range_max_m", 2.5),
    ("detection_min_range_m", "detection.range_min_m", 0.02),
    ("camera_enabled", "camera.enabled", True),
    ("camera_width", "camera.width", 640),
    ("camera_height", "camera.height", 480),
    ("camera_hfov_rad", "camera.horizontal_fov_rad", math.radians(70.0)),
    ("camera_rate_hz", "camera.rate_hz", 15.0),
    ("camera_mount_z_m", "camera.mount_z_m", 0.10),
    ("camera_pitch_rad", "camera.pitch_rad", 0.0),
    ("camera_noise", "camera.noise_sigma", 2.0),
    ("camera_exposure_s", "camera.exposure_s", 0.008),
    ("camera_gain", "camera.gain", 1.0),
    ("localisation_error", "localisation.error", (0.0, 0.0, 0.0)),
    ("odom_noise", "odom.noise", 0.0),
]


@pytest.mark.parametrize(("old", "new", "value"), FLAT_DEFAULTS, ids=[old for old, _n, _v in FLAT_DEFAULTS])
def test_each_flat_default_lives_on_under_its_component(old: str, new: str, value: object) -> None:
    found: object = Params(world=SEED_ROOM)
    for part in new.split("."):
        found = getattr(found, part)
    if isinstance(value, tuple):
        found = tuple(found)  # type: ignore[arg-type]
    assert found == pytest.approx(value) if isinstance(value, float) else found == value, f"{old} -> {new}"
