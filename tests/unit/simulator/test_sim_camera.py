"""The camera's image of the world's geometry: each column's runs of surfaces, background and floor."""

from __future__ import annotations

import math

import numpy as np
import pytest

from services.simulator.camera import (
    BACKGROUND_GREY,
    CameraParams,
    CameraRenderer,
    Surface,
    _ColumnSpans,
    build_scene,
)
from shared.geometry import Pose2D
from shared.world import parse_world


def _reference(
    running_top: np.ndarray,
    hit: np.ndarray,
    foot_row: np.ndarray,
    layer_grey: np.ndarray,
    floor_grey: np.ndarray,
) -> np.ndarray:
    """Pixel by pixel: the nearest layer whose top is at or above the row, down to the nearest layer's foot;
    the floor's grey elsewhere."""
    W, k = hit.shape
    H = len(floor_grey)
    image = np.empty((H, W), dtype=np.float32)
    for c in range(W):
        for r in range(H):
            shown = math.nan
            if r <= foot_row[c]:
                for j in range(k):
                    if hit[c, j] and math.ceil(running_top[c, j]) <= r:
                        shown = layer_grey[c, j]
                        break
            image[r, c] = floor_grey[r] if math.isnan(shown) else shown
    return image


@pytest.mark.parametrize("seed", range(6))
def test_column_spans_paint_what_each_pixel_shows(seed: int) -> None:
    rng = np.random.default_rng(seed)
    W, H, k = 23, 31, 4
    hits = rng.integers(0, k + 1, size=W)  # how many layers each column crosses, nearest first
    hit = np.arange(k)[None, :] < hits[:, None]
    tops = rng.uniform(-5.0, H + 5.0, size=(W, k))
    running_top = np.minimum.accumulate(np.where(hit, tops, np.inf), axis=1)
    foot_row = rng.uniform(-3.0, H + 3.0, size=W)
    layer_grey = rng.uniform(0.0, 255.0, size=(W, k)).astype(np.float32)
    layer_grey[~hit] = np.nan
    floor_grey = rng.uniform(0.0, 255.0, size=H).astype(np.float32)

    spans = _ColumnSpans.of_layers(running_top, hit, foot_row, H)
    painted = spans.paint(layer_grey, floor_grey)

    assert painted.shape == (W, H), "column by column"
    np.testing.assert_array_equal(painted.T, _reference(running_top, hit, foot_row, layer_grey, floor_grey))
    for j in range(k):  # each layer's span holds exactly the pixels that show it
        columns = np.flatnonzero(hit[:, j])
        start, end = spans.of_layer(columns, np.full(len(columns), j))
        for c, lo, hi in zip(columns, start, end, strict=True):
            assert np.all(painted[c, lo:hi] == layer_grey[c, j])


def test_a_wall_ahead_fills_the_rows_between_its_top_and_its_foot() -> None:
    world = parse_world(
        {
            "name": "wall_ahead",
            "bounds": [-10.0, -10.0, 10.0, 10.0],
            "walls": [[[2.0, -5.0], [2.0, 5.0]]],
            "docks": [{"id": "d", "pose": [-9.0, 0.0, 0.0]}],
            "robot": {"start": [0.0, 0.0, 0.0]},
        }
    )
    params = CameraParams(noise_sigma=0.0, width=64, height=48)
    image = CameraRenderer(build_scene(world), params).render(Pose2D(-params.mount_x_m, 0.0, 0.0))
    f, (cx, cy) = params.focal_px, params.centre_px
    wall = next(s for s in build_scene(world).surfaces if s.a == (2.0, -5.0))
    assert isinstance(wall, Surface)
    top = cy - f * (wall.height_m - params.mount_z_m) / 2.0
    foot = cy + f * params.mount_z_m / 2.0
    column = image[:, int(cx)].astype(float)
    inside = np.arange(48)[(np.arange(48) >= math.ceil(top)) & (np.arange(48) <= foot)]
    assert len(inside) > 5 and np.ptp(column[inside]) == 0, "a flat-shaded wall is one grey"
    assert np.all(column[: math.ceil(top)] == np.uint8(BACKGROUND_GREY)), "above the wall: the background"
    assert np.all(column[int(foot) + 1 :] != column[inside[0]]), "below its foot: the floor"
