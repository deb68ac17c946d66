"""Occupancy maps in memory and on disk, in the ROS map_server format (YAML + PGM image).

In memory the map mirrors ``nav_msgs/OccupancyGrid``: an int8 array indexed ``data[iy, ix]`` with row 0
at the origin (lowest y), values -1 unknown, 0 free, 100 occupied. On disk the image is the other way up:
PGM row 0 is the top of the map (highest y). Loading follows map_server (nav2_map_server ``map_io``):
a pixel ``v`` out of ``maxval`` has occupancy probability ``p = (maxval - v) / maxval`` (``v / maxval``
with ``negate``); in ``trinary`` mode ``p > occupied_thresh`` is occupied, ``p < free_thresh`` free,
anything between unknown.
"""

from __future__ import annotations

import json
import logging
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import msgspec
import numpy as np

from services.planner.grid_frame import GridFrame
from shared.config_errors import ConfigError, read_yaml_file
from shared.structs import field_names, validate

log = logging.getLogger(__name__)

OCC_UNKNOWN = -1
OCC_FREE = 0
OCC_OCCUPIED = 100

#: Pixel values written by :func:`save_map` (the map_saver convention: black, light grey, white).
PIXEL_OCCUPIED = 0
PIXEL_UNKNOWN = 205
PIXEL_FREE = 254
#: Thresholds written by :func:`save_map`. The unknown grey 205 reads back as p = 50/255 = 0.19608,
#: which is not below 0.196, so it stays unknown; 254 (p = 0.0039) is free and 0 (p = 1) occupied.
SAVED_OCCUPIED_THRESH = 0.65
SAVED_FREE_THRESH = 0.196


@dataclass(eq=False)
class OccupancyMap:
    """A 2-D occupancy grid: ``data[iy, ix]`` in {-1, 0..100}, row 0 at ``origin``'s y."""

    resolution_m: float
    #: Pose ``(x, y, yaw)`` of cell (0, 0)'s outer corner in the map frame.
    origin: tuple[float, float, float]
    data: np.ndarray

    def __post_init__(self) -> None:
        data = np.asarray(self.data)
        if data.ndim != 2:
            raise ValueError(f"occupancy data must be a 2-D (height, width) array, got shape {data.shape}")
        if data.size and (data.min() < OCC_UNKNOWN or data.max() > OCC_OCCUPIED):
            raise ValueError("occupancy values must be -1 (unknown) or 0..100")
        self.data = data.astype(np.int8, copy=False)
        self.origin = tuple(float(v) for v in self.origin)  # type: ignore[assignment]
        self.resolution_m = float(self.resolution_m)
        GridFrame(self.resolution_m, self.origin, self.width, self.height)  # validates the resolution

    @property
    def width(self) -> int:
        return int(self.data.shape[1])

    @property
    def height(self) -> int:
        return int(self.data.shape[0])

    @property
    def frame(self) -> GridFrame:
        """The grid's geometry, shared with costmaps built from this map."""
        return GridFrame(self.resolution_m, self.origin, self.width, self.height)

    def world_to_cell(self, x: float, y: float) -> tuple[int, int]:
        """``(ix, iy)`` of the cell holding ``(x, y)``; may lie outside the grid (see :meth:`in_bounds`)."""
        return self.frame.world_to_cell(x, y)

    def cell_to_world(self, ix: int, iy: int) -> tuple[float, float]:
        """Centre of cell ``(ix, iy)`` in the map frame."""
        return self.frame.cell_to_world(ix, iy)

    def in_bounds(self, ix: int, iy: int) -> bool:
        return 0 <= ix < self.width and 0 <= iy < self.height

    def value_at(self, x: float, y: float) -> int:
        """Occupancy at a world point; unknown (-1) off the grid."""
        ix, iy = self.world_to_cell(x, y)
        return int(self.data[iy, ix]) if self.in_bounds(ix, iy) else OCC_UNKNOWN


class _MapYaml(msgspec.Struct, frozen=True, kw_only=True):
    """The map_server YAML fields. Unknown keys are ignored, with a warning (:func:`load_map`)."""

    image: str
    resolution: float
    origin: tuple[float, float, float]
    negate: bool = False
    occupied_thresh: float
    free_thresh: float
    mode: Literal["trinary", "scale", "raw"] = "trinary"

    def __post_init__(self) -> None:
        if not self.image.strip():
            raise ValueError("image: must name the map's image file")
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise ValueError(
                f"resolution: must be a positive number of metres per cell, got {self.resolution}"
            )
        if not all(math.isfinite(c) for c in self.origin):
            raise ValueError(f"origin: must be three finite numbers [x, y, yaw], got {list(self.origin)}")
        for name in ("occupied_thresh", "free_thresh"):
            if not (0.0 <= getattr(self, name) <= 1.0):
                raise ValueError(f"{name}: must be a probability between 0 and 1, got {getattr(self, name)}")
        if self.free_thresh > self.occupied_thresh:
            raise ValueError(
                f"free_thresh ({self.free_thresh}) must not exceed occupied_thresh ({self.occupied_thresh})"
            )


_PGM_COMMENT = re.compile(rb"#[^\n\r]*")


def read_pgm(path: str | Path) -> tuple[np.ndarray, int]:
    """Read a binary (P5) or ASCII (P2) PGM: ``(pixels[row, col] as int, maxval)``, row 0 at the top."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read map image: {exc.strerror or exc}") from None
    magic = raw[:2]
    if magic not in (b"P5", b"P2"):
        raise ConfigError(f"{path}: not a PGM image (expected magic P5 or P2, got {magic!r})")
    # Header: three integers (width, height, maxval) separated by whitespace, with '#' comments.
    pos = 2
    header: list[int] = []
    while len(header) < 3:
        while pos < len(raw) and raw[pos : pos + 1].isspace():
            pos += 1
        if pos >= len(raw):
            raise ConfigError(f"{path}: PGM header ends early (need width, height, maxval)")
        if raw[pos : pos + 1] == b"#":
            while pos < len(raw) and raw[pos : pos + 1] not in (b"\n", b"\r"):
                pos += 1
            continue
        start = pos
        while pos < len(raw) and raw[pos : pos + 1].isdigit():
            pos += 1
        if start == pos:
            raise ConfigError(f"{path}: PGM header: expected a number at byte {start}")
        header.append(int(raw[start:pos]))
    width, height, maxval = header
    if width <= 0 or height <= 0 or not (0 < maxval < 65536):
        raise ConfigError(f"{path}: PGM header: bad size {width}x{height} or maxval {maxval}")
    count = width * height
    if magic == b"P5":
        body = raw[pos + 1 :]  # exactly one whitespace byte separates maxval from the pixels
        dtype = np.dtype(">u2") if maxval > 255 else np.dtype(np.uint8)
        if len(body) < count * dtype.itemsize:
            raise ConfigError(f"{path}: PGM pixel data is short: {len(body)} bytes for {width}x{height}")
        pixels = np.frombuffer(body, dtype=dtype, count=count).astype(np.int64)
    else:
        try:
            values = [int(t) for t in _PGM_COMMENT.sub(b" ", raw[pos:]).split()]
        except ValueError:
            raise ConfigError(f"{path}: ASCII PGM holds a value that is not an integer") from None
        if len(values) < count:
            raise ConfigError(f"{path}: ASCII PGM has {len(values)} pixels, expected {width}x{height}")
        pixels = np.array(values[:count], dtype=np.int64)
    if pixels.max(initial=0) > maxval:
        raise ConfigError(f"{path}: PGM pixel value above maxval {maxval}")
    return pixels.reshape(height, width), maxval


def write_pgm(path: str | Path, pixels: np.ndarray) -> None:
    """Write 8-bit pixels ``[row, col]`` (row 0 at the top) as a binary P5 PGM."""
    pixels = np.asarray(pixels, dtype=np.uint8)
    height, width = pixels.shape
    header = f"P5\n# zendock occupancy map\n{width} {height}\n255\n".encode("ascii")
    Path(path).write_bytes(header + pixels.tobytes())


def occupancy_from_pixels(
    pixels: np.ndarray, maxval: int, negate: bool, occupied_thresh: float, free_thresh: float, mode: str
) -> np.ndarray:
    """map_server's pixel -> occupancy rule (image rows as given, top row first)."""
    pixels = np.asarray(pixels)
    if mode == "raw":
        return np.where((pixels >= OCC_FREE) & (pixels <= OCC_OCCUPIED), pixels, OCC_UNKNOWN).astype(np.int8)
    shade = pixels.astype(float) / float(maxval)
    occ = shade if negate else 1.0 - shade
    out = np.full(pixels.shape, OCC_UNKNOWN, dtype=np.int8)
    if mode == "scale" and occupied_thresh > free_thresh:
        scaled = np.rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100.0)
        out = np.clip(scaled, 0, 100).astype(np.int8)
    out[occ > occupied_thresh] = OCC_OCCUPIED
    out[occ < free_thresh] = OCC_FREE
    return out


def load_map(yaml_path: str | Path) -> OccupancyMap:
    """Load a map_server YAML and its image. Raises :class:`ConfigError` naming the file and field."""
    yaml_path = Path(yaml_path)
    doc: Any = read_yaml_file(yaml_path, "map file")
    if not isinstance(doc, dict):
        raise ConfigError(
            f"{yaml_path}: a map file must be a mapping with image, resolution, origin, "
            f"occupied_thresh, free_thresh; got {type(doc).__name__}"
        )
    spec = validate(_MapYaml, doc, yaml_path)
    for key in sorted(set(map(str, doc)) - set(field_names(_MapYaml))):
        log.warning("%s: unknown key %r ignored", yaml_path, key)
    image_path = Path(spec.image)
    if not image_path.is_absolute():
        image_path = yaml_path.parent / image_path
    if not image_path.is_file():
        raise ConfigError(f"{yaml_path}: image: no such file {image_path}")
    pixels, maxval = read_pgm(image_path)
    top_first = occupancy_from_pixels(
        pixels, maxval, spec.negate, spec.occupied_thresh, spec.free_thresh, spec.mode
    )
    return OccupancyMap(resolution_m=spec.resolution, origin=spec.origin, data=np.flipud(top_first).copy())


def pixels_from_occupancy(data: np.ndarray) -> np.ndarray:
    """map_saver's trinary rule: occupied (>= 65) black, free (<= 19) white, the rest unknown grey."""
    data = np.asarray(data)
    pixels = np.full(data.shape, PIXEL_UNKNOWN, dtype=np.uint8)
    pixels[(data >= 0) & (data <= math.floor(SAVED_FREE_THRESH * 100))] = PIXEL_FREE
    pixels[data >= math.ceil(SAVED_OCCUPIED_THRESH * 100)] = PIXEL_OCCUPIED
    return pixels


def save_map(occupancy_map: OccupancyMap, yaml_path: str | Path) -> tuple[Path, Path]:
    """Write ``<name>.yaml`` and ``<name>.pgm`` (trinary) side by side; returns both paths."""
    yaml_path = Path(yaml_path)
    pgm_path = yaml_path.with_suffix(".pgm")
    yaml_path.parent.mkdir(parents=True, exist_ok=True)
    write_pgm(pgm_path, np.flipud(pixels_from_occupancy(occupancy_map.data)))
    x, y, yaw = occupancy_map.origin
    yaml_path.write_text(
        f"image: {json.dumps(pgm_path.name)}\n"
        "mode: trinary\n"
        f"resolution: {occupancy_map.resolution_m!r}\n"
        f"origin: [{x!r}, {y!r}, {yaw!r}]\n"
        "negate: 0\n"
        f"occupied_thresh: {SAVED_OCCUPIED_THRESH}\n"
        f"free_thresh: {SAVED_FREE_THRESH}\n"
    )
    return yaml_path, pgm_path
