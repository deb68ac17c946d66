"""From pixels to dock poses: ArUco detection, the marker's pose by IPPE, and the dock it stands for.

Steps, each one OpenCV's well-kept implementation where one exists:

1. :class:`MarkerFinder` finds markers with ``cv2.aruco.ArucoDetector`` (corners refined to sub-pixel),
   then moves each corner onto the intersection of the marker's fitted outer edges (:func:`refine_corners`).
2. :func:`marker_poses` solves the perspective-n-point problem for the square (``solvePnPGeneric`` with
   ``SOLVEPNP_IPPE_SQUARE``), which returns both poses a planar square admits: at a distance the two differ
   mainly in the marker's tilt and one of them is the mirror image of the truth.
3. What the robot knows about its docks settles the rest: the marker stands upright on a vertical face at
   a known height, so only its floor position and heading are unknown. A solution that cannot be made
   upright is refused (a reflection, a marker lying down, a bad detection); each upright one seeds a
   three-unknown refinement (:func:`refine_upright`) and the better fit wins.
4. The marker's pose in base_link becomes the dock's pose (the docked base_link pose) through the dock
   geometry: the marker is on the dock's face, ``ROBOT_FRONT_M`` ahead of the docked robot, facing it.

Nothing here touches the bus; the perception service and the perception benchmark share it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from shared.geometry import Pose2D
from shared.rigid3 import Rigid3
from shared.world import ROBOT_FRONT_M, DockMarker

#: A solution whose normal tilts further than this from horizontal is not an upright marker.
MAX_TILT_RAD = math.radians(25.0)
#: The dock pose (docked base_link) seen from the marker's frame on the dock's face.
_DOCK_FROM_MARKER = Pose2D(ROBOT_FRONT_M, 0.0, math.pi)


@dataclass(frozen=True, slots=True)
class MarkerSighting:
    """One marker found in an image: its id and its four corners (pixels, ArUco's order)."""

    marker_id: int
    corners: np.ndarray  # (4, 2) float64: top-left, top-right, bottom-right, bottom-left


@dataclass(frozen=True, slots=True)
class MarkerPose:
    """One solution for the marker's pose: marker frame (x right, y up, z out of the face) in base_link."""

    base_from_marker: Rigid3
    reprojection_error_px: float

    @property
    def normal(self) -> np.ndarray:
        return self.base_from_marker.rotation[:, 2]

    @property
    def tilt_rad(self) -> float:
        """How far the marker's normal leans out of the horizontal plane."""
        return abs(math.asin(max(-1.0, min(1.0, float(self.normal[2])))))


@dataclass(frozen=True, slots=True)
class DockSighting:
    """A dock found by its marker: the dock pose in base_link, and how it was found."""

    dock_id: str
    marker_id: int
    dock_in_base: Pose2D
    marker_range_m: float
    reprojection_error_px: float
    tilt_rad: float


#: The largest adaptive-threshold window (px) when searching boxes around known markers (OpenCV's default
#: is 23, with windows 3, 13 and 23).
BOX_THRESHOLD_WINDOW_MAX_PX = 13


def _detector_parameters(threshold_window_max_px: int | None = None) -> cv2.aruco.DetectorParameters:
    """ArUco's defaults with sub-pixel corner refinement, and at most this threshold window when given."""
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    params.cornerRefinementWinSize = 4
    params.cornerRefinementMaxIterations = 50
    params.cornerRefinementMinAccuracy = 0.01
    if threshold_window_max_px is not None:
        params.adaptiveThreshWinSizeMax = threshold_window_max_px
    return params


class MarkerFinder:
    """ArUco detection for one dictionary, with sub-pixel corner refinement."""

    def __init__(self, dictionary: str) -> None:
        try:
            family = getattr(cv2.aruco, dictionary)
        except AttributeError:
            raise ValueError(f"unknown ArUco dictionary {dictionary!r}") from None
        self.dictionary = dictionary
        markers = cv2.aruco.getPredefinedDictionary(family)
        self._cells_across = int(markers.markerSize) + 2
        self._detector = cv2.aruco.ArucoDetector(markers, _detector_parameters())
        # A box around a marker seen a frame ago is thresholded at two window sizes instead of three: the
        # same markers, found more cheaply (measurement 63), and a miss is searched for again in the whole
        # frame with all three.
        self._box_detector = cv2.aruco.ArucoDetector(
            markers, _detector_parameters(BOX_THRESHOLD_WINDOW_MAX_PX)
        )

    def find(
        self, grey: np.ndarray, regions: Sequence[tuple[int, int, int, int]] | None = None
    ) -> list[MarkerSighting]:
        """Markers in the whole image, or only within ``regions`` (``(x0, y0, x1, y1)`` pixel boxes, end
        exclusive): the detector's cost grows with the pixels it thresholds, and a marker found a frame ago
        is still near where it was. Corners are refined on the whole image either way."""
        found: dict[int, np.ndarray] = {}
        for x0, y0, x1, y1 in regions if regions is not None else [(0, 0, grey.shape[1], grey.shape[0])]:
            crop = np.ascontiguousarray(grey[y0:y1, x0:x1])  # the whole image is already contiguous: no copy
            if crop.size == 0:
                continue
            detector = self._detector if regions is None else self._box_detector
            corners, ids, _rejected = detector.detectMarkers(crop)
            if ids is None:
                continue
            for i, c in zip(ids.ravel(), corners, strict=True):
                found.setdefault(int(i), np.asarray(c, dtype=np.float64).reshape(4, 2) + (x0, y0))
        return [MarkerSighting(i, refine_corners(grey, c, self._cells_across)) for i, c in found.items()]


_PROFILE_STEP_PX = 0.1
_SIDE_SAMPLES = 16


def refine_corners(grey: np.ndarray, corners: np.ndarray, cells_across: int = 6) -> np.ndarray:
    """Corners moved onto the intersections of the marker's four outer edges, each edge located by the
    area of its grey-level step between the black border and the white surround.

    ``cornerSubPix`` pulls a small marker's corners about 0.2 px inwards (its window meets the inner
    cells), which at 2 m is a 2 % range error. The step's area locates a straight edge without bias,
    and sixteen samples per side average the noise. Sides shorter than
    three cells' worth of profile, or a refinement that moves a corner by more than 1.5 px, keep the
    detector's corners.
    """
    quad = np.asarray(corners, dtype=np.float64).reshape(4, 2)
    centre = quad.mean(axis=0)
    side_px = float(np.mean(np.linalg.norm(np.roll(quad, -1, axis=0) - quad, axis=1)))
    cell_px = side_px / cells_across
    if cell_px < 2.0:
        return quad
    reach = 0.5 * cell_px
    offsets = np.arange(-reach, reach + 1e-9, _PROFILE_STEP_PX)
    along = np.linspace(0.2, 0.8, _SIDE_SAMPLES)
    # The four sides at once: side i runs from corner i to corner i + 1.
    side = np.roll(quad, -1, axis=0) - quad  # (4, 2)
    t = side / np.linalg.norm(side, axis=1, keepdims=True)
    n = np.stack([-t[:, 1], t[:, 0]], axis=1)
    outwards = (
        np.sum((quad + side / 2.0 - centre) * n, axis=1) >= 0
    )  # from the black border to the white surround
    n[~outwards] *= -1.0
    base = quad[:, None, :] + along[None, :, None] * side[:, None, :]  # (4, K, 2)
    pts = base[:, :, None, :] + offsets[None, None, :, None] * n[:, None, None, :]  # (4, K, M, 2)
    K, M = len(along), len(offsets)
    profile = cv2.remap(
        grey,
        pts[..., 0].reshape(4 * K, M).astype(np.float32),
        pts[..., 1].reshape(4 * K, M).astype(np.float32),
        cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_REPLICATE,
    ).astype(np.float64)
    dark = profile[:, :3].mean(axis=1, keepdims=True)
    light = profile[:, -3:].mean(axis=1, keepdims=True)
    contrast = (light - dark).reshape(4, K)
    # Where a step from dark to light sits is the profile's area above dark, measured from the light
    # end: exact for a pixel-integrated (box-sampled) edge and for any symmetric blur, where a
    # halfway crossing found by interpolation is off by up to 0.09 px with the edge's sub-pixel phase.
    level = np.clip((profile - dark) / np.maximum(light - dark, 1e-9), 0.0, 1.0)
    area = (level.sum(axis=1) - 0.5 * (level[:, 0] + level[:, -1])) * _PROFILE_STEP_PX
    edge_offsets = (offsets[-1] - area).reshape(4, K)
    edge_points = base + edge_offsets[:, :, None] * n[:, None, :]  # (4, K, 2)
    steep = contrast >= 20.0
    if np.any(steep.sum(axis=1) < _SIDE_SAMPLES // 2):
        return quad
    lines = []
    for i in range(4):
        vx, vy, x0, y0 = cv2.fitLine(
            edge_points[i][steep[i]].astype(np.float32), cv2.DIST_L2, 0, 0.01, 0.01
        ).ravel()
        lines.append((np.array([x0, y0], dtype=np.float64), np.array([vx, vy], dtype=np.float64)))
    refined = np.empty_like(quad)
    for i in range(4):
        # corner i is where side i-1 (ending at it) meets side i (starting from it)
        (p1, d1), (p2, d2) = lines[i - 1], lines[i]
        matrix = np.array([d1, -d2]).T
        if abs(np.linalg.det(matrix)) < 1e-9:
            return quad
        s_t = np.linalg.solve(matrix, p2 - p1)
        refined[i] = p1 + s_t[0] * d1
    if float(np.max(np.linalg.norm(refined - quad, axis=1))) > 1.5:
        return quad
    return refined


def marker_object_points(size_m: float) -> np.ndarray:
    """The square's corners in its own frame, in the order IPPE_SQUARE requires (and ArUco reports)."""
    h = size_m / 2.0
    return np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]])


def marker_poses(
    sighting: MarkerSighting,
    size_m: float,
    camera_matrix: np.ndarray,
    distortion: np.ndarray,
    base_from_optical: Rigid3,
) -> list[MarkerPose]:
    """Both IPPE solutions for the marker, in base_link, best reprojection first."""
    ok, rvecs, tvecs, errors = cv2.solvePnPGeneric(
        marker_object_points(size_m),
        sighting.corners,
        camera_matrix,
        distortion,
        flags=cv2.SOLVEPNP_IPPE_SQUARE,
    )
    if not ok:
        return []
    poses = []
    for rvec, tvec, err in zip(rvecs, tvecs, np.asarray(errors).ravel(), strict=True):
        rotation, _ = cv2.Rodrigues(rvec)
        optical_from_marker = Rigid3(rotation, np.asarray(tvec, dtype=np.float64).ravel())
        poses.append(MarkerPose(base_from_optical.compose(optical_from_marker), float(err)))
    poses.sort(key=lambda p: p.reprojection_error_px)
    return poses


def choose_pose(poses: Sequence[MarkerPose]) -> MarkerPose | None:
    """Of the solutions that stand the marker upright, the one that reprojects best; None when neither is
    upright enough (a reflection, a marker lying down, or a bad detection)."""
    upright = [p for p in poses if p.tilt_rad <= MAX_TILT_RAD]
    return min(upright, key=lambda p: p.reprojection_error_px) if upright else None


def upright_marker(pose: MarkerPose) -> Pose2D:
    """The marker's floor-plane pose: where it stands, and its normal's heading."""
    n = pose.normal
    t = pose.base_from_marker.translation
    return Pose2D(float(t[0]), float(t[1]), math.atan2(float(n[1]), float(n[0])))


#: The upright marker's corners (ArUco's order) in its own plane, in half sides: (right, up).
_CORNER_SIGNS = ((-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0))


def refine_upright(
    start: Pose2D,
    observed_norm: np.ndarray,
    size_m: float,
    centre_height_m: float,
    base_from_optical: Rigid3,
    iterations: int = 30,
) -> tuple[Pose2D, float]:
    """Levenberg-Marquardt on the marker's three planar unknowns (x, y, heading), its height and uprightness known.

    ``observed_norm`` are the corners in normalised image coordinates (undistorted). Eight residuals for
    three unknowns: far better conditioned than six unknowns for a small marker at a distance, which is
    where a free pose's heading wanders. Returns the pose and the RMS residual in normalised units.

    The perception service runs this for every seed of every frame. Four corners and three unknowns are
    too few for numpy to pay off (each array operation costs more than its arithmetic), so the
    projection, its exact Jacobian and the 3 x 3 normal equations are plain floats: cheaper than central
    differences on arrays, with the same fit (measurement 57).
    """
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = (
        base_from_optical.rotation.T.tolist()
    )  # optical <- base
    tx, ty, tz = base_from_optical.translation.tolist()
    h = size_m / 2.0
    corners = [(h * su, centre_height_m + h * sv - tz) for su, sv in _CORNER_SIGNS]
    observed = [tuple(p) for p in np.asarray(observed_norm, dtype=np.float64).reshape(4, 2).tolist()]

    def project(
        x: float, y: float, yaw: float, with_jacobian: bool
    ) -> tuple[list[float], list[tuple[float, float, float]]]:
        c, s = math.cos(yaw), math.sin(yaw)
        residual: list[float] = []
        jacobian: list[tuple[float, float, float]] = []
        for (u, height), (ox, oy) in zip(corners, observed, strict=True):
            # Corner at (x - u sin(yaw), y + u cos(yaw), height) in base_link, then into the optical frame.
            bx, by = x - u * s - tx, y + u * c - ty
            a = r00 * bx + r01 * by + r02 * height
            b = r10 * bx + r11 * by + r12 * height
            z = r20 * bx + r21 * by + r22 * height
            z = z if z > 1e-6 else 1e-6
            pa, pb = a / z, b / z
            residual += (pa - ox, pb - oy)
            if with_jacobian:
                # d(base)/d(x, y, yaw) = (1, 0, 0), (0, 1, 0), (-u cos, -u sin, 0); d(a / z) = (da - (a / z) dz) / z.
                dbx, dby = -u * c, -u * s
                dz_yaw = r20 * dbx + r21 * dby
                jacobian.append(
                    ((r00 - pa * r20) / z, (r01 - pa * r21) / z, (r00 * dbx + r01 * dby - pa * dz_yaw) / z)
                )
                jacobian.append(
                    ((r10 - pb * r20) / z, (r11 - pb * r21) / z, (r10 * dbx + r11 * dby - pb * dz_yaw) / z)
                )
        return residual, jacobian

    def squared(values: list[float]) -> float:
        return math.fsum(v * v for v in values)

    x, y, yaw = start.x, start.y, start.yaw
    r, J = project(x, y, yaw, True)
    cost = squared(r)
    damping = 1e-3
    for _ in range(iterations):
        JtJ = [[math.fsum(row[i] * row[j] for row in J) for j in range(3)] for i in range(3)]
        Jtr = [math.fsum(row[i] * ri for row, ri in zip(J, r, strict=True)) for i in range(3)]
        while damping < 1e8:  # Levenberg-Marquardt: shorten the step until it helps
            A = [
                [JtJ[i][j] + (damping * (JtJ[i][i] + 1e-12) if i == j else 0.0) for j in range(3)]
                for i in range(3)
            ]
            delta = _solve3(A, [-v for v in Jtr])
            r_new, _ = project(x + delta[0], y + delta[1], yaw + delta[2], False)
            cost_new = squared(r_new)
            if cost_new < cost:
                x, y, yaw, cost = x + delta[0], y + delta[1], yaw + delta[2], cost_new
                r, J = project(x, y, yaw, True)
                damping = max(damping / 10.0, 1e-9)
                break
            damping *= 10.0
        else:
            break
        if max(abs(d) for d in delta) < 1e-8:
            break
    return Pose2D(x, y, yaw), math.sqrt(squared(r) / 4.0)


def _solve3(A: list[list[float]], rhs: list[float]) -> list[float]:
    """``A x = rhs`` for a 3 x 3 system by Cramer's rule (A is the damped normal matrix: never singular)."""
    (a, b, c), (d, e, f), (g, h, i) = A
    p, q, r = rhs
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    x0 = (p * (e * i - f * h) - b * (q * i - f * r) + c * (q * h - e * r)) / det
    x1 = (a * (q * i - f * r) - p * (d * i - f * g) + c * (d * r - q * g)) / det
    x2 = (a * (e * r - q * h) - b * (d * r - q * g) + p * (d * h - e * g)) / det
    return [x0, x1, x2]


def facing_seed(observed_norm: np.ndarray, size_m: float, base_from_optical: Rigid3) -> Pose2D:
    """A starting guess that needs no PnP: the marker straight along its centre's ray, at the range its
    apparent size gives, facing the camera. IPPE's two solutions degenerate for a marker seen face-on,
    where this guess is at its best."""
    side = float(np.mean(np.linalg.norm(observed_norm - np.roll(observed_norm, 1, axis=0), axis=1)))
    ray = np.append(observed_norm.mean(axis=0), 1.0)
    centre = base_from_optical.apply(ray * (size_m / max(side, 1e-9)))
    camera = base_from_optical.translation
    return Pose2D(
        float(centre[0]), float(centre[1]), math.atan2(camera[1] - centre[1], camera[0] - centre[0])
    )


#: Two fits this close in residual explain the corners about equally well: the marker's pose is ambiguous.
AMBIGUOUS_RESIDUAL_RATIO = 2.0
#: The previous pose settles an ambiguity only when it is this much nearer one fit's heading than the other's;
#: a previous pose about as far from both (the view jumped, or the robot turned a lot) says nothing.
CONTINUITY_MARGIN_RAD = math.radians(8.0)
#: With the dock database's heading to go by (the robot's pose known), fits up to this many times worse than
#: the best stay candidates: a small, far marker's mirror solution can fit better than the truth in every
#: frame (2.5 m and 30 degrees aside in the simulator's images: about half the truth's residual), which
#: no continuity can undo; the database's heading is 60 degrees from it there.
EXPECTED_RESIDUAL_RATIO = 4.0
#: Fits whose headings differ by less than this are one solution (seeds that converged to the same fit).
SAME_FIT_RAD = math.radians(1.0)


def choose_fit(
    fits: Sequence[tuple[float, Pose2D]],
    previous: Pose2D | None,
    ambiguous_ratio: float = AMBIGUOUS_RESIDUAL_RATIO,
) -> tuple[float, Pose2D]:
    """The fit to believe among ``(residual, marker pose)`` fits: the best residual, unless another explains
    the corners nearly as well (within ``AMBIGUOUS_RESIDUAL_RATIO``) and a recent ``previous`` pose is clearly
    nearer one of them in heading (by ``CONTINUITY_MARGIN_RAD``): then that one (continuity, since a planar
    square's mirror solution differs mostly in heading). A previous pose about equally far from both would
    only lock in a coin toss, so the residual decides."""
    ranked = sorted(fits, key=lambda f: f[0])
    best = ranked[0]
    if previous is None:
        return best
    rivals: list[tuple[float, Pose2D]] = []
    for fit in ranked:
        if fit[0] > ambiguous_ratio * max(best[0], 1e-6):
            break
        if all(abs(math.remainder(fit[1].yaw - r[1].yaw, math.tau)) >= SAME_FIT_RAD for r in rivals):
            rivals.append(fit)
    if len(rivals) < 2:
        return best

    def turn(fit: tuple[float, Pose2D]) -> float:
        return abs(math.remainder(fit[1].yaw - previous.yaw, math.tau))

    nearest, runner_up = sorted(rivals, key=turn)[:2]
    return nearest if turn(runner_up) - turn(nearest) >= CONTINUITY_MARGIN_RAD else best


def locate_dock(
    sighting: MarkerSighting,
    marker: DockMarker,
    camera_matrix: np.ndarray,
    distortion: np.ndarray,
    base_from_optical: Rigid3,
    previous: Pose2D | None = None,
    expected: Pose2D | None = None,
) -> DockSighting | None:
    """The dock a sighted marker belongs to, in base_link; None when no upright pose explains the corners.

    Each upright IPPE solution, and a face-on guess (:func:`facing_seed`), seeds a planar refinement
    (:func:`refine_upright`); the fit with the smaller residual wins, which settles the mirror ambiguity of
    a square seen from the side, unless the fits are nearly as good: then ``expected`` (the dock database's
    pose in base_link, from the robot's pose) picks the one nearer its heading, among fits up to
    ``EXPECTED_RESIDUAL_RATIO`` worse; without it, ``previous`` (the dock's pose in base_link a moment ago)
    picks the one that continues it (:func:`choose_fit`).
    """
    poses = [
        p
        for p in marker_poses(sighting, marker.size_m, camera_matrix, distortion, base_from_optical)
        if p.tilt_rad <= MAX_TILT_RAD
    ]
    if not poses:
        return None
    observed = cv2.undistortPoints(sighting.corners.reshape(-1, 1, 2), camera_matrix, distortion).reshape(
        -1, 2
    )
    focal = float(camera_matrix[0, 0])
    seeds = [upright_marker(p) for p in poses] + [facing_seed(observed, marker.size_m, base_from_optical)]
    fits = []
    for seed in seeds:
        fitted, residual = refine_upright(
            seed, observed, marker.size_m, marker.centre_height_m, base_from_optical
        )
        fits.append((residual, fitted))
    if expected is not None:
        residual, fitted = choose_fit(
            fits, expected.compose(_DOCK_FROM_MARKER.inverse()), EXPECTED_RESIDUAL_RATIO
        )
    else:
        previous_marker = previous.compose(_DOCK_FROM_MARKER.inverse()) if previous is not None else None
        residual, fitted = choose_fit(fits, previous_marker)
    pose = poses[0]
    centre = np.array([fitted.x, fitted.y, marker.centre_height_m])
    return DockSighting(
        dock_id=marker.dock_id,
        marker_id=marker.marker_id,
        dock_in_base=fitted.compose(_DOCK_FROM_MARKER),
        marker_range_m=float(np.linalg.norm(centre - base_from_optical.translation)),
        reprojection_error_px=residual * focal,
        tilt_rad=pose.tilt_rad,
    )


__all__ = [
    "DockSighting",
    "MarkerFinder",
    "MarkerPose",
    "MarkerSighting",
    "choose_fit",
    "choose_pose",
    "facing_seed",
    "locate_dock",
    "marker_object_points",
    "marker_poses",
    "refine_corners",
    "refine_upright",
    "upright_marker",
]
