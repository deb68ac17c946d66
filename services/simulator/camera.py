"""The forward camera: a pinhole image of the world, rendered from its geometry.

The world is a floor plane with vertical surfaces standing on it (walls, box sides, the docks' bodies, glass
panes), each of a stated height. With the camera level, a vertical surface is a vertical strip in the image,
so one ray per image column finds every surface the column crosses (:func:`~shared.models.raycast`'s
segment tests, vectorised over columns and surfaces). A pixel shows the nearest surface whose top is above
it, or the floor below the nearest surface's foot: occlusion, perspective and the horizon follow from the
geometry. Each dock's face carries its ArUco marker, warped into the image by the homography of the marker's
four projected corners from a texture of about the size it appears (no aliasing at a distance, sharp near).
Glass is nearly transparent: a faint sheen over whatever lies behind. A pitched camera is the level image
rotated about the optical centre, a homography as well (``K R K^-1``).

After the geometry comes the sensor: exposure gain, motion blur along the image rows for the camera's turn
during the exposure, and Gaussian read noise. Nothing here knows where the marker "should" be detected: the
perception service must find it in the pixels.

The module imports numpy and OpenCV only (no bus); it is the simulator's and the perception benchmark's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from types import ModuleType
from typing import Annotated

import numpy as np
from msgspec import Meta

from services.simulator.sensors import CAMERA_MOUNT_X_M
from shared.geometry import Pose2D
from shared.models.component import ComponentParams
from shared.world import DOCK_GEOMETRY, Dock, DockMarker, World, dock_markers

#: OpenCV's pixel convention: pixel centres sit at integer coordinates, the image spans [-0.5, n - 0.5].
_OPAQUE_LAYERS = 8
#: Marker pixels are the average of this many samples a side (area coverage at the edges).
_SUPERSAMPLE = 3


_OPENCV: list[ModuleType] = []


def opencv(threads: int = 0) -> ModuleType:
    """OpenCV, imported with the first rendered frame rather than at start-up: it is the heaviest of the
    simulator's imports (measurement 82), and a run that nobody watches through the camera (the synthetic
    detector's) never renders a frame. ``threads`` (0: OpenCV's default) is set on that first import."""
    if not _OPENCV:
        import cv2  # noqa: PLC0415

        cv2.setNumThreads(threads or -1)  # -1: OpenCV's default
        _OPENCV.append(cv2)
    return _OPENCV[0]


class CameraParams(ComponentParams, frozen=True):
    """A pinhole camera on ``camera_link``, ``mount_x_m`` ahead of base_link and ``mount_z_m`` above the floor.

    ``pitch_rad`` tilts it down (REP 103: a positive rotation about camera_link's y axis). ``noise_sigma``
    is read noise in grey levels; ``exposure_s`` sets motion blur; ``gain`` scales brightness. The
    simulator renders frames only while someone subscribes (``enabled: false``: no camera at all).
    """

    enabled: Annotated[
        bool, Meta(description="render camera/image_raw and camera/camera_info (while subscribed)")
    ] = True
    width: Annotated[int, Meta(ge=16, le=4096)] = 640
    height: Annotated[int, Meta(ge=16, le=4096)] = 480
    horizontal_fov_rad: Annotated[float, Meta(gt=0.1, lt=2.6)] = math.radians(70.0)
    rate_hz: Annotated[float, Meta(gt=0)] = 15.0
    mount_x_m: float = CAMERA_MOUNT_X_M
    mount_z_m: Annotated[float, Meta(gt=0)] = 0.10
    pitch_rad: Annotated[float, Meta(gt=-1.04, lt=1.04)] = 0.0
    noise_sigma: Annotated[float, Meta(ge=0, description="read noise, grey levels (sigma)")] = 2.0
    exposure_s: Annotated[float, Meta(ge=0, description="exposure time: sets motion blur")] = 0.008
    gain: Annotated[float, Meta(gt=0)] = 1.0
    near_m: float = 0.01
    opencv_threads: Annotated[
        int,
        Meta(
            ge=0,
            description="threads OpenCV may use for the simulator's process (0: one "
            "per core); one is cheaper where the cores are busy (measurement 62)",
        ),
    ] = 1

    @property
    def focal_px(self) -> float:
        return 0.5 * self.width / math.tan(0.5 * self.horizontal_fov_rad)

    @property
    def centre_px(self) -> tuple[float, float]:
        return (self.width - 1) / 2.0, (self.height - 1) / 2.0

    def intrinsics(self) -> np.ndarray:
        """K, the 3x3 camera matrix (square pixels, no skew, no distortion)."""
        f = self.focal_px
        cx, cy = self.centre_px
        return np.array([[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]])

    @property
    def mount(self) -> Pose2D:
        """camera_link on base_link, in the floor plane."""
        return Pose2D(self.mount_x_m, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class Surface:
    """A vertical rectangle standing on the floor from ``a`` to ``b`` (seen from either side)."""

    a: tuple[float, float]
    b: tuple[float, float]
    height_m: float
    albedo: float
    glass: bool = False
    #: The index into the scene's markers when this is a dock's face carrying its marker.
    marker: int | None = None


@dataclass(frozen=True)
class Scene:
    """What the camera can see of a world, prepared once: surfaces as arrays, markers with textures."""

    surfaces: tuple[Surface, ...]
    markers: tuple[DockMarker, ...]
    a: np.ndarray = field(repr=False)
    d: np.ndarray = field(repr=False)  # b - a
    heights: np.ndarray = field(repr=False)
    albedo: np.ndarray = field(repr=False)
    normal_angle: np.ndarray = field(repr=False)
    opaque: np.ndarray = field(repr=False)
    marker_faces: np.ndarray = field(repr=False)

    @classmethod
    def from_surfaces(cls, surfaces: list[Surface], markers: list[DockMarker]) -> Scene:
        a = np.array([s.a for s in surfaces], dtype=np.float64).reshape(-1, 2)
        b = np.array([s.b for s in surfaces], dtype=np.float64).reshape(-1, 2)
        d = b - a
        return cls(
            tuple(surfaces),
            tuple(markers),
            a,
            d,
            np.array([s.height_m for s in surfaces], dtype=np.float64),
            np.array([s.albedo for s in surfaces], dtype=np.float64),
            np.arctan2(d[:, 0], -d[:, 1]) if len(surfaces) else np.zeros(0),
            np.array([not s.glass for s in surfaces], dtype=bool),
            np.array([s.marker is not None for s in surfaces], dtype=bool),
        )


#: Heights (m) and brightness (0..1) of what the world file describes.
WALL_HEIGHT_M = 0.60
BOX_HEIGHT_M = 0.45
GLASS_HEIGHT_M = 1.00
WALL_ALBEDO = 0.72
BOX_ALBEDO = 0.50
DOCK_BODY_ALBEDO = 0.30
DOCK_FACE_ALBEDO = 0.92
MARKER_BLACK = 0.06
#: Another robot as the camera sees it: a box of its footprint, this high, this bright.
ROBOT_BODY_HEIGHT_M = 0.25
ROBOT_BODY_ALBEDO = 0.22
FLOOR_ALBEDO = 0.40
BACKGROUND_GREY = 35.0


def build_scene(world: World) -> Scene:
    """The world as the camera sees it: bounds and walls, box sides, dock bodies with marked faces, glass."""
    surfaces: list[Surface] = []
    xmin, ymin, xmax, ymax = world.bounds
    ring = [(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax)]
    for i in range(4):
        surfaces.append(Surface(ring[i], ring[(i + 1) % 4], WALL_HEIGHT_M, WALL_ALBEDO))
    for a, b in world.walls:
        surfaces.append(Surface(a, b, WALL_HEIGHT_M, WALL_ALBEDO))
    for box in world.boxes:
        c = box.corners()
        surfaces += [Surface(c[i], c[(i + 1) % 4], BOX_HEIGHT_M, BOX_ALBEDO) for i in range(4)]
    markers = dock_markers(world)
    for index, (dock, marker) in enumerate(zip(world.docks, markers, strict=True)):
        surfaces += _dock_surfaces(dock, marker, index)
    for a, b in world.glass:
        surfaces.append(Surface(a, b, GLASS_HEIGHT_M, 0.0, glass=True))
    return Scene.from_surfaces(surfaces, markers)


def _dock_surfaces(dock: Dock, marker: DockMarker, index: int) -> list[Surface]:
    height = max(DOCK_GEOMETRY.body_height_m, marker.centre_height_m + marker.size_m / 2 + 0.03)
    c = DOCK_GEOMETRY.body_box(dock).corners()
    # Box corners run counter-clockwise from (-depth/2, -width/2): the face towards the robot joins the
    # last corner to the first.
    sides = [Surface(c[i], c[i + 1], height, DOCK_BODY_ALBEDO) for i in range(3)]
    return [*sides, Surface(c[3], c[0], height, DOCK_FACE_ALBEDO, marker=index)]


@dataclass(frozen=True, slots=True)
class Motion:
    """The camera's motion during the exposure: forward speed (m/s) and turn rate (rad/s)."""

    linear_mps: float = 0.0
    angular_radps: float = 0.0


class ReadNoise:
    """Gaussian read noise for whole frames: windows at random offsets into a bank of two frames' worth.

    Drawing fresh normals costs more than the rest of the sensor model; a shifted window is as good for a
    detector (independent per pixel within a frame, different from frame to frame). The bank is 2.4 MB
    for a 640 x 480 frame, so the cameras of one process (a simulator's robots) share one: each draws
    its own offsets from its own generator.
    """

    def __init__(self, rng: np.random.Generator) -> None:
        self._rng = rng
        self._bank = np.zeros(0, dtype=np.float32)
        self._sigma = math.nan

    def window(self, n: int, sigma: float, rng: np.random.Generator) -> np.ndarray:
        """``n`` pixels' noise of standard deviation ``sigma`` (a view into the bank: do not write to it)."""
        if len(self._bank) < 2 * n or sigma != self._sigma:
            self._bank = self._rng.standard_normal(2 * n, dtype=np.float32)
            self._bank *= np.float32(sigma)
            self._sigma = sigma
        start = int(rng.integers(0, n))
        return self._bank[start : start + n]


class CameraRenderer:
    """Renders ``scene`` through a camera with ``params``: :meth:`render` gives a mono8 image."""

    def __init__(
        self,
        scene: Scene,
        params: CameraParams,
        rng: np.random.Generator | None = None,
        noise: ReadNoise | None = None,
    ) -> None:
        """``noise``: a bank shared with the other cameras of the process (one is made when None)."""
        self.scene = scene
        self.params = params
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self._K = params.intrinsics()
        self._level = _LevelView.for_params(params)
        self.noise = noise if noise is not None else ReadNoise(self.rng)

    def camera_pose(self, robot_pose: Pose2D) -> Pose2D:
        return robot_pose.compose(self.params.mount)

    def marker_pixels(self, marker: DockMarker, robot_pose: Pose2D) -> np.ndarray | None:
        """Where the marker's corners (ArUco's order) fall in the image, exactly; None when behind the camera.
        The yardstick for corner accuracy."""
        cv2 = opencv(self.params.opencv_threads)
        level = self._level
        pts = _project(
            marker_corners_world(marker), self.camera_pose(robot_pose), self.params.mount_z_m, level
        )
        if pts is None or level.warp is None:
            return pts
        return cv2.perspectiveTransform(pts.reshape(-1, 1, 2), level.warp).reshape(-1, 2)

    def render(
        self, robot_pose: Pose2D, motion: Motion = Motion(), others: Sequence[np.ndarray] = ()
    ) -> np.ndarray:
        """The camera's image (uint8, height x width) with the robot's base_link at ``robot_pose``;
        ``others``: the footprints (4 x 2 corners) of other robots in the room, drawn as dark boxes."""
        p = self.params
        cv2 = opencv(p.opencv_threads)
        level = self._level
        scene = self.scene
        if len(others):
            bodies = [
                Surface(tuple(c[i]), tuple(c[(i + 1) % 4]), ROBOT_BODY_HEIGHT_M, ROBOT_BODY_ALBEDO)
                for c in others
                for i in range(4)
            ]
            scene = Scene.from_surfaces([*scene.surfaces, *bodies], list(scene.markers))
        # The level view comes column by column (its transpose): a level camera's columns are runs of flat
        # grey. The sensor model works on it as it is, and one uint8 transpose at the end gives the image.
        image = self._render_level(self.camera_pose(robot_pose), level, scene)
        by_column = level.warp is None
        if level.warp is not None:
            image = cv2.warpPerspective(
                cv2.transpose(image),
                level.warp,
                (p.width, p.height),
                flags=cv2.INTER_LINEAR,
                borderMode=cv2.BORDER_REPLICATE,
            )
        # ``image`` is a fresh array: scaled, blurred and clipped in place.
        if p.gain != 1.0:
            image *= np.float32(p.gain)
        blur_px = abs(motion.angular_radps) * p.exposure_s * p.focal_px
        if blur_px >= 1.0:  # along the image's rows
            k = int(round(blur_px)) | 1
            image = np.asarray(cv2.blur(image, (1, k) if by_column else (k, 1)), dtype=np.float32)
        if p.noise_sigma > 0:
            image += self.noise.window(image.size, p.noise_sigma, self.rng).reshape(image.shape)
        np.clip(image, 0, 255, out=image)
        out = image.astype(np.uint8)
        return np.asarray(cv2.transpose(out)) if by_column else out

    # --- geometry ------------------------------------------------------------------------------------

    def _render_level(self, camera: Pose2D, view: _LevelView, scene: Scene) -> np.ndarray:
        """Radiance (float32 grey levels) of a level camera at ``camera`` on ``view``'s canvas, transposed:
        (width, height), one image column after another."""
        p = self.params
        f, cy = view.focal_px, view.cy
        h_cam = p.mount_z_m
        cos_y, sin_y = math.cos(camera.yaw), math.sin(camera.yaw)
        forward = np.array([cos_y, sin_y])
        right = np.array([sin_y, -cos_y])
        a = view.column_slopes  # (W,): X/Z of each column
        rays = forward[None, :] + a[:, None] * right[None, :]  # (W, 2): Z-depth 1 along each
        W, H = view.width, view.height
        # Floor and background, row by row (below the horizon the floor's depth is f h / (row - cy)).
        rows = view.rows
        below = rows > cy + 1e-6
        floor_depth = np.where(below, f * h_cam / np.maximum(rows - cy, 1e-6), np.inf)
        floor_grey = 255.0 * FLOOR_ALBEDO * (0.55 + 0.45 * np.exp(-floor_depth / 4.0))
        floor_grey = np.where(below, floor_grey, BACKGROUND_GREY).astype(np.float32)
        depth, along = _intersect(np.array([camera.x, camera.y]), rays, scene.a, scene.d, p.near_m)  # (W, S)
        o_depth = np.where(scene.opaque[None, :], depth, np.inf)
        # Layers: as many as the column with the most opaque hits has (at most _OPAQUE_LAYERS).
        k = min(_OPAQUE_LAYERS, int(np.isfinite(o_depth).sum(axis=1).max())) if len(scene.surfaces) else 0
        if not k:
            image = np.empty((W, H), dtype=np.float32)
            image[:] = floor_grey[None, :]
            nearest_depth = np.full(W, np.inf)
        else:
            if k < o_depth.shape[1]:  # the k nearest of each column, then those k in order
                order = np.argpartition(o_depth, k - 1, axis=1)[:, :k]
                order = np.take_along_axis(
                    order, np.argsort(np.take_along_axis(o_depth, order, axis=1), axis=1), axis=1
                )
            else:
                order = np.argsort(o_depth, axis=1)
            layer_depth = np.take_along_axis(o_depth, order, axis=1)
            hit = np.isfinite(layer_depth)  # a prefix of each row: misses sort last
            tops = cy - f * (scene.heights[order] - h_cam) / layer_depth  # row of each layer's top edge
            running_top = np.minimum.accumulate(np.where(hit, tops, np.inf), axis=1)  # non-increasing
            # Flat shading per layer and column: brighter when seen face-on.
            ray_angle = np.arctan2(rays[:, 1], rays[:, 0])
            facing = np.abs(np.cos(ray_angle[:, None] - scene.normal_angle[order]))
            shade = (255.0 * scene.albedo[order] * (0.35 + 0.65 * facing)).astype(np.float32)
            nearest_depth = layer_depth[:, 0]
            spans = _ColumnSpans.of_layers(running_top, hit, cy + f * h_cam / nearest_depth, H)
            image = spans.paint(np.where(hit, shade, np.float32(np.nan)), floor_grey)
            # Each marker face lies in at most one layer of a column: its pixels are that layer's span.
            for surface_index in np.unique(order[scene.marker_faces[order] & hit]):
                in_layer = (order == surface_index) & hit  # (W, k)
                columns = np.flatnonzero(in_layer.any(axis=1))
                start, end = spans.of_layer(columns, in_layer[columns].argmax(axis=1))
                if not np.any(end > start):
                    continue  # hidden behind nearer surfaces everywhere
                marker_index = scene.surfaces[int(surface_index)].marker
                assert marker_index is not None
                self._paint_marker(image, columns, start, end, camera, scene, marker_index, view)
        self._paint_glass(image, depth, nearest_depth, cy, f, h_cam, scene)
        return image

    def _paint_glass(
        self,
        image: np.ndarray,
        depth: np.ndarray,
        nearest_opaque: np.ndarray,
        cy: float,
        f: float,
        h_cam: float,
        scene: Scene,
    ) -> None:
        glass = ~scene.opaque
        if not glass.any():
            return
        rows = self._level.rows
        for s in np.flatnonzero(glass):
            d = depth[:, s]
            seen = np.isfinite(d) & (d < nearest_opaque)
            if not seen.any():
                continue
            cols = np.flatnonzero(seen)
            top = cy - f * (scene.heights[s] - h_cam) / d[cols]
            bottom = cy + f * h_cam / d[cols]
            mask = (rows[None, :] >= top[:, None]) & (rows[None, :] <= bottom[:, None])
            sub = image[cols]
            image[cols] = np.where(mask, 0.88 * sub + 0.12 * 235.0, sub)

    def _paint_marker(
        self,
        image: np.ndarray,
        columns: np.ndarray,
        start: np.ndarray,
        end: np.ndarray,
        camera: Pose2D,
        scene: Scene,
        marker_index: int,
        view: _LevelView,
    ) -> None:
        """Replace the face's flat white with the marker, warped by the homography of its corners. The face
        shows in rows ``[start, end)`` of each of ``columns`` (ascending)."""
        cv2 = opencv(self.params.opencv_threads)
        marker = scene.markers[marker_index]
        corners = marker_corners_world(marker)  # (4, 3): TL, TR, BR, BL
        pts = _project(corners, camera, self.params.mount_z_m, view)
        if pts is None:
            return
        side_px = float(np.max(np.linalg.norm(pts - np.roll(pts, 1, axis=0), axis=1)))
        # A large marker needs no supersampling to put its edges right; a whole-image one would cost 9x.
        ss = _SUPERSAMPLE if side_px < 120 else (2 if side_px < 240 else 1)
        texture = marker_texture(marker.dictionary, marker.marker_id, _texture_size(ss * side_px))
        n = texture.shape[0]
        src = np.array([[-0.5, -0.5], [n - 0.5, -0.5], [n - 0.5, n - 0.5], [-0.5, n - 0.5]], dtype=np.float32)
        # Only the marker's own box (within the face's) changes: the rest of the face stays plain white.
        visible = end > start
        columns, start, end = columns[visible], start[visible], end[visible]
        x0 = max(int(columns[0]), math.floor(float(pts[:, 0].min())) - 1)
        x1 = min(int(columns[-1]) + 1, math.ceil(float(pts[:, 0].max())) + 2)
        y0 = max(int(start.min()), math.floor(float(pts[:, 1].min())) - 1)
        y1 = min(int(end.max()), math.ceil(float(pts[:, 1].max())) + 2)
        if x1 <= x0 or y1 <= y0:
            return
        # Warp onto a grid ``ss`` times finer over the face's bounding box, then average each ss x ss block:
        # every pixel gets the ink's area coverage, so the marker's edges fall where its corners project.
        # Fine pixel (i, j) has its centre at image ((i + 0.5) / ss - 0.5 + x0, ...).
        to_fine = np.array(
            [[ss, 0, ss * (0.5 - x0) - 0.5], [0, ss, ss * (0.5 - y0) - 0.5], [0, 0, 1]], dtype=np.float64
        )
        H = to_fine @ cv2.getPerspectiveTransform(src, pts.astype(np.float32))
        fine = cv2.warpPerspective(
            texture,
            H,
            (int(x1 - x0) * ss, int(y1 - y0) * ss),
            flags=cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_CONSTANT,
            borderValue=255,
        )
        if ss > 1:
            fine = cv2.resize(fine, (int(x1 - x0), int(y1 - y0)), interpolation=cv2.INTER_AREA)
        # The face's lit white times the ink's reflectance, one float32 temporary for the whole box.
        shade = fine.astype(np.float32)
        shade *= np.float32((DOCK_FACE_ALBEDO - MARKER_BLACK) / (255.0 * DOCK_FACE_ALBEDO))
        shade += np.float32(MARKER_BLACK / DOCK_FACE_ALBEDO)
        region = image[x0:x1, y0:y1].T  # the image is column by column
        shade *= region
        first, last = np.full(x1 - x0, y1), np.zeros(x1 - x0, dtype=start.dtype)
        inside = (columns >= x0) & (columns < x1)
        first[columns[inside] - x0], last[columns[inside] - x0] = start[inside], end[inside]
        box_rows = np.arange(y0, y1)[:, None]
        np.copyto(region, shade, where=(box_rows >= first[None, :]) & (box_rows < last[None, :]))


@dataclass(frozen=True)
class _ColumnSpans:
    """Where each depth layer shows in each column of a level view, as rows ``[start, end)``.

    Going down a column the image shows the background, then the layers from the farthest one still
    visible to the nearest, then the floor below the nearest one's foot. Each layer's run is one flat grey,
    so the image is a single run-length expansion of these spans, column by column, rather than one pass
    over every pixel per layer.
    """

    #: (W, k + 2) row boundaries: the background's run starts at column 0, layer j's at ``k - j``, the
    #: floor below the nearest layer's foot at ``k + 1``.
    bounds: np.ndarray
    height: int

    @classmethod
    def of_layers(
        cls, running_top: np.ndarray, hit: np.ndarray, foot_row: np.ndarray, height: int
    ) -> _ColumnSpans:
        """``running_top``: (W, k) the highest top row of the layers up to each, nearest first (non-increasing);
        ``hit``: which layers exist; ``foot_row``: the nearest layer's foot row in each column."""
        W, k = running_top.shape
        bounds = np.empty((W, k + 2), dtype=np.int64)
        bounds[:, 0] = 0
        # Layer j shows from the first row under every nearer layer's top; a missing layer from row 0.
        first_row = np.where(hit, np.clip(np.ceil(running_top), 0, height), 0)
        bounds[:, 1 : k + 1] = first_row[:, ::-1]
        # Rows at or above the nearest layer's foot show layers; the floor shows below it.
        bounds[:, k + 1] = np.clip(np.floor(foot_row) + 1, 0, height)
        np.minimum(bounds, bounds[:, k + 1 :], out=bounds)
        return cls(bounds, height)

    def of_layer(self, columns: np.ndarray, layer: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The rows ``[start, end)`` where ``layer[i]`` shows in ``columns[i]``."""
        run = self.bounds.shape[1] - 2 - layer
        return self.bounds[columns, run], self.bounds[columns, run + 1]

    def paint(self, layer_grey: np.ndarray, floor_grey: np.ndarray) -> np.ndarray:
        """The float32 image, transposed (W, H): ``layer_grey`` (W, k) on each layer's run (NaN: the floor
        shows there), ``floor_grey`` (H,) on the rest, row by row."""
        W, k = layer_grey.shape
        grey = np.empty((W, k + 2), dtype=np.float32)
        grey[:, 0] = np.nan
        grey[:, 1 : k + 1] = layer_grey[:, ::-1]
        grey[:, k + 1] = np.nan
        lengths = np.diff(self.bounds, axis=1, append=self.height)
        by_column = np.repeat(grey.ravel(), lengths.ravel()).reshape(W, self.height)
        np.copyto(by_column, floor_grey[None, :], where=np.isnan(by_column))
        return by_column


@dataclass(frozen=True)
class _LevelView:
    """The level camera's canvas: tall enough that a pitched view warps from it without gaps."""

    width: int
    height: int
    focal_px: float
    cx: float
    cy: float
    warp: np.ndarray | None
    rows: np.ndarray
    column_slopes: np.ndarray

    @classmethod
    def for_params(cls, p: CameraParams) -> _LevelView:
        f = p.focal_px
        cx, cy = p.centre_px
        if p.pitch_rad == 0.0:
            return cls(
                p.width,
                p.height,
                f,
                cx,
                cy,
                None,
                np.arange(p.height, dtype=np.float64),
                (np.arange(p.width) - cx) / f,
            )
        K = p.intrinsics()
        # The pitched camera's rays in the level camera's frame (optical axes: x right, y down, z ahead).
        c, s = math.cos(p.pitch_rad), math.sin(p.pitch_rad)
        R = np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])  # pitched optical -> level optical
        corners = np.array(
            [
                [-0.5, -0.5, 1],
                [p.width - 0.5, -0.5, 1],
                [p.width - 0.5, p.height - 0.5, 1],
                [-0.5, p.height - 0.5, 1],
            ],
            dtype=np.float64,
        ).T
        level = R @ np.linalg.inv(K) @ corners
        rows = f * level[1] / level[2] + cy
        cols = f * level[0] / level[2] + cx
        top, bottom = math.floor(rows.min()) - 2, math.ceil(rows.max()) + 2
        left, right = math.floor(min(cols.min(), -0.5)) - 2, math.ceil(max(cols.max(), p.width - 0.5)) + 2
        width, height = right - left, bottom - top
        Kc = np.array([[f, 0.0, cx - left], [0.0, f, cy - top], [0.0, 0.0, 1.0]])
        warp = Kc @ R @ np.linalg.inv(K)  # output pixel -> canvas pixel
        return cls(
            width,
            height,
            f,
            cx - left,
            cy - top,
            np.linalg.inv(warp) / 1.0,
            np.arange(height, dtype=np.float64),
            (np.arange(width) - (cx - left)) / f,
        )


def _intersect(
    origin: np.ndarray, rays: np.ndarray, a: np.ndarray, d: np.ndarray, near: float
) -> tuple[np.ndarray, np.ndarray]:
    """Depth along each ray (in units of the ray vector) to each segment, inf when it misses; and where along."""
    # origin + t r = a + u d  ->  t r - u d = a - origin
    rx, ry = rays[:, 0:1], rays[:, 1:2]
    dx, dy = d[None, :, 0], d[None, :, 1]
    wx, wy = (a[:, 0] - origin[0])[None, :], (a[:, 1] - origin[1])[None, :]
    den = -rx * dy + ry * dx
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (-wx * dy + wy * dx) / den
        u = (rx * wy - ry * wx) / den
    hit = (np.abs(den) > 1e-12) & (t > near) & (u >= 0.0) & (u <= 1.0)
    return np.where(hit, t, np.inf), np.where(hit, u, np.nan)


def marker_corners_world(marker: DockMarker) -> np.ndarray:
    """The marker's corners in the world (x, y, z), in ArUco's order: top-left, top-right, bottom-right,
    bottom-left as seen facing the marker."""
    half = marker.size_m / 2.0
    m = marker.pose  # x axis out of the dock, towards the viewer
    # Facing the marker, the viewer's right is the marker frame's +y (its x axis points at the viewer).
    rx, ry = -math.sin(m.yaw), math.cos(m.yaw)
    z = marker.centre_height_m
    out = []
    for right, up in ((-half, half), (half, half), (half, -half), (-half, -half)):
        out.append((m.x + right * rx, m.y + right * ry, z + up))
    return np.array(out)


def _project(points: np.ndarray, camera: Pose2D, h_cam: float, view: _LevelView) -> np.ndarray | None:
    """Image points of world points on the level canvas; None when any is behind the camera."""
    dx, dy = points[:, 0] - camera.x, points[:, 1] - camera.y
    c, s = math.cos(camera.yaw), math.sin(camera.yaw)
    ahead = c * dx + s * dy
    left = -s * dx + c * dy
    if np.any(ahead <= 1e-3):
        return None
    u = view.cx + view.focal_px * (-left) / ahead
    v = view.cy + view.focal_px * (-(points[:, 2] - h_cam)) / ahead
    return np.stack([u, v], axis=1)


def _texture_size(side_px: float) -> int:
    """A texture a little larger than the marker appears (bilinear sampling then neither aliases nor blurs)."""
    size = 12
    while size < 1.5 * side_px and size < 768:
        size *= 2
    return size


@lru_cache(maxsize=64)
def marker_texture(dictionary: str, marker_id: int, size_px: int) -> np.ndarray:
    """The marker's ink, uint8 (255 is white), ``size_px`` a side, border cells included."""
    cv2 = opencv()
    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    cells = d.markerSize + 2
    # Draw at a whole number of pixels per cell, then resample with area averaging to the size asked.
    per_cell = max(1, math.ceil(size_px / cells))
    img = cv2.aruco.generateImageMarker(d, marker_id, cells * per_cell)
    if img.shape[0] != size_px:
        img = cv2.resize(img, (size_px, size_px), interpolation=cv2.INTER_AREA)
    return img


__all__ = [
    "CameraParams",
    "CameraRenderer",
    "Motion",
    "Scene",
    "Surface",
    "build_scene",
    "marker_corners_world",
    "marker_texture",
]
