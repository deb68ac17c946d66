"""Frame names, sensor mounts from tf_static, and clock resets."""

from __future__ import annotations

from shared.frames import CLOCK_RESET_S, SensorMounts, clock_went_back, frame_name
from shared.geometry import Pose2D
from shared.messages import Header, TFMessage, Transform, TransformStamped


def _mount(parent: str, child: str, pose: Pose2D) -> TransformStamped:
    return TransformStamped(
        header=Header(frame_id=parent), child_frame_id=child, transform=Transform.from_pose2d(pose)
    )


def test_frame_names_ignore_leading_slashes() -> None:
    assert frame_name("/base_link") == frame_name("base_link") == "base_link"
    assert frame_name("//odom") == "odom"


def test_mounts_take_base_link_children_whatever_the_slashes() -> None:
    mounts = SensorMounts({"/lidar_link": Pose2D(0.1, 0.0, 0.0)})
    assert mounts.get("lidar_link") == Pose2D(0.1, 0.0, 0.0)
    sonar = Pose2D(0.2, 0.05, 0.3)
    updated = mounts.update(
        TFMessage(
            transforms=[
                _mount("/base_link", "/sonar_link", sonar),
                _mount("odom", "elsewhere", Pose2D(5, 5, 0)),
            ]
        )
    )
    assert updated == ["sonar_link"]
    got = mounts.get("/sonar_link")
    assert got is not None and got.distance_to(sonar) < 1e-9 and abs(got.yaw - sonar.yaw) < 1e-9
    assert mounts.get("elsewhere") is None


def test_a_clock_reset_is_a_jump_back_beyond_jitter() -> None:
    assert not clock_went_back(10.0, None)
    assert not clock_went_back(10.0 - 0.5 * CLOCK_RESET_S, 10.0)
    assert clock_went_back(10.0 - 2 * CLOCK_RESET_S, 10.0)
