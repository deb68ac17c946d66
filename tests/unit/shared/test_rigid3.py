"""3-D rigid transforms: composition, the REP 103 optical rotation, and chains of static frames."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shared.rigid3 import OPTICAL_FROM_LINK_QUATERNION, Rigid3, StaticTransforms, quaternion_from_pitch


def test_the_optical_frame_looks_along_the_links_x_with_x_right_and_y_down() -> None:
    optical = Rigid3.from_parts((0.0, 0.0, 0.0), OPTICAL_FROM_LINK_QUATERNION)
    assert np.allclose(optical.rotation[:, 2], [1, 0, 0])  # optical z (ahead) is link x
    assert np.allclose(optical.rotation[:, 0], [0, -1, 0])  # optical x (right) is link -y
    assert np.allclose(optical.rotation[:, 1], [0, 0, -1])  # optical y (down) is link -z


def test_a_positive_pitch_looks_down() -> None:
    pitched = Rigid3.from_parts((0.0, 0.0, 0.0), quaternion_from_pitch(math.radians(10)))
    ahead = pitched.apply(np.array([1.0, 0.0, 0.0]))
    assert ahead[2] == pytest.approx(-math.sin(math.radians(10)))


def test_chains_compose_in_order_and_missing_links_give_none() -> None:
    frames = StaticTransforms()
    frames.set("base_link", "camera_link", Rigid3.from_parts((0.15, 0.0, 0.10), (0.0, 0.0, 0.0, 1.0)))
    frames.set(
        "camera_link",
        "camera_optical_frame",
        Rigid3.from_parts((0.0, 0.0, 0.0), OPTICAL_FROM_LINK_QUATERNION),
    )
    chain = frames.lookup("base_link", "camera_optical_frame")
    assert chain is not None
    assert np.allclose(chain.apply(np.array([0.0, 0.0, 2.0])), [2.15, 0.0, 0.10])
    assert frames.lookup("base_link", "lidar_link") is None


def test_a_non_unit_quaternion_is_refused() -> None:
    with pytest.raises(ValueError):
        Rigid3.from_parts((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0))
