"""3-D rigid transforms: composition, the REP 103 optical rotation, and chains of static frames."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shared.messages import Header, Quaternion, TFMessage, Transform, TransformStamped, Vector3
from shared.rigid3 import OPTICAL_FROM_LINK_QUATERNION, Rigid3, quaternion_from_pitch
from shared.tf_buffer import TfBuffer, rigid3_between


def test_the_optical_frame_looks_along_the_links_x_with_x_right_and_y_down() -> None:
    optical = Rigid3.from_parts((0.0, 0.0, 0.0), OPTICAL_FROM_LINK_QUATERNION)
    assert np.allclose(optical.rotation[:, 2], [1, 0, 0])  # optical z (ahead) is link x
    assert np.allclose(optical.rotation[:, 0], [0, -1, 0])  # optical x (right) is link -y
    assert np.allclose(optical.rotation[:, 1], [0, 0, -1])  # optical y (down) is link -z


def test_a_positive_pitch_looks_down() -> None:
    pitched = Rigid3.from_parts((0.0, 0.0, 0.0), quaternion_from_pitch(math.radians(10)))
    ahead = pitched.apply(np.array([1.0, 0.0, 0.0]))
    assert ahead[2] == pytest.approx(-math.sin(math.radians(10)))


def test_a_camera_mount_chains_through_the_tf_buffer_and_a_missing_one_is_none() -> None:
    frames = TfBuffer()

    def link(
        parent: str, child: str, xyz: tuple[float, float, float], q: tuple[float, ...]
    ) -> TransformStamped:
        return TransformStamped(
            header=Header(frame_id=parent),
            child_frame_id=child,
            transform=Transform(translation=Vector3(*xyz), rotation=Quaternion(*q)),
        )

    msg = TFMessage(
        transforms=[
            link("base_link", "camera_link", (0.15, 0.0, 0.10), (0.0, 0.0, 0.0, 1.0)),
            link("camera_link", "camera_optical_frame", (0.0, 0.0, 0.0), OPTICAL_FROM_LINK_QUATERNION),
        ]
    )
    assert frames.add_message(msg, static=True).refused == []
    chain = rigid3_between(frames, "base_link", "camera_optical_frame")
    assert chain is not None
    assert np.allclose(chain.apply(np.array([0.0, 0.0, 2.0])), [2.15, 0.0, 0.10])
    assert rigid3_between(frames, "base_link", "lidar_link") is None


def test_a_non_unit_quaternion_is_refused() -> None:
    with pytest.raises(ValueError):
        Rigid3.from_parts((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0))
