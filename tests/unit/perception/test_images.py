"""Image payloads: each malformed frame is refused with the reason named; valid encodings become grey."""

from __future__ import annotations

import numpy as np
import pytest

from services.perception.images import ImageError, grey_pixels
from shared.messages import Header, Image, Time


def _image(height: int, width: int, encoding: str, step: int, data: np.ndarray) -> Image:
    return Image(Header(Time(), "camera_optical_frame"), height, width, encoding, 0, step, data)


@pytest.mark.parametrize(
    ("image", "reason"),
    [
        (_image(4, 4, "yuv422", 8, np.zeros(32, np.uint8)), "encoding"),
        (_image(0, 4, "mono8", 4, np.zeros(0, np.uint8)), "empty"),
        (_image(4, 4, "rgb8", 4, np.zeros(16, np.uint8)), "step"),
        (_image(4, 4, "mono8", 4, np.zeros(10, np.uint8)), "size"),
    ],
)
def test_malformed_frames_are_refused_with_a_reason(image: Image, reason: str) -> None:
    with pytest.raises(ImageError) as caught:
        grey_pixels(image)
    assert caught.value.reason == reason


def test_padded_rows_and_colour_encodings_become_the_same_grey() -> None:
    grey = np.arange(12, dtype=np.uint8).reshape(3, 4) * 20
    padded = np.zeros((3, 6), np.uint8)
    padded[:, :4] = grey
    assert np.array_equal(grey_pixels(_image(3, 4, "mono8", 6, padded.ravel())), grey)
    rgb = np.repeat(grey[:, :, None], 3, axis=2)
    assert np.array_equal(grey_pixels(_image(3, 4, "rgb8", 12, rgb.ravel())), grey)
    bgra = np.concatenate([rgb, np.full((3, 4, 1), 255, np.uint8)], axis=2)
    assert np.array_equal(grey_pixels(_image(3, 4, "bgra8", 16, bgra.ravel())), grey)
