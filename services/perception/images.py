"""sensor_msgs/Image payloads checked and turned into grey pixels for the detector.

A frame is refused, with a reason a log line can name, when its encoding is not one the detector reads,
its dimensions are zero, its ``step`` is shorter than a row, or its data is not ``height * step`` bytes.
"""

from __future__ import annotations

import cv2
import numpy as np

from shared.messages import Image

#: Encodings read, and the bytes per pixel of each.
CHANNELS = {"mono8": 1, "rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4}


class ImageError(ValueError):
    """A frame the detector cannot read; ``reason`` is a short name for counters."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason


def grey_pixels(msg: Image) -> np.ndarray:
    """The frame as a (height, width) uint8 array (a view when it is mono8 with no row padding)."""
    channels = CHANNELS.get(msg.encoding)
    if channels is None:
        raise ImageError(
            "encoding", f"unknown image encoding {msg.encoding!r} (known: {', '.join(CHANNELS)})"
        )
    if msg.height == 0 or msg.width == 0:
        raise ImageError("empty", f"image of {msg.width}x{msg.height} pixels")
    if msg.step < msg.width * channels:
        raise ImageError(
            "step", f"step {msg.step} is shorter than a row of {msg.width} {msg.encoding} pixels"
        )
    if msg.data.size != msg.height * msg.step:
        raise ImageError("size", f"{msg.data.size} bytes of data for {msg.height} rows of {msg.step} bytes")
    rows = msg.data.reshape(msg.height, msg.step)[:, : msg.width * channels]
    if channels == 1:
        return rows
    pixels = rows.reshape(msg.height, msg.width, channels)
    code = {
        "rgb8": cv2.COLOR_RGB2GRAY,
        "bgr8": cv2.COLOR_BGR2GRAY,
        "rgba8": cv2.COLOR_RGBA2GRAY,
        "bgra8": cv2.COLOR_BGRA2GRAY,
    }[msg.encoding]
    return cv2.cvtColor(np.ascontiguousarray(pixels), code)
