"""Convex-polygon geometry for the robot's rectangular footprint: overlap and distance.

Overlap is the separating-axis theorem (Gottschalk et al., "OBBTree", SIGGRAPH 1996): two convex
polygons are disjoint iff their projections on some edge normal of either do not overlap. A segment is a
two-vertex polygon here.
"""

from __future__ import annotations

import numpy as np

from shared.geometry import Pose2D
from shared.world import ROBOT_LENGTH_M, ROBOT_WIDTH_M


def footprint_corners(
    pose: Pose2D, length_m: float = ROBOT_LENGTH_M, width_m: float = ROBOT_WIDTH_M
) -> np.ndarray:
    """The robot's rectangular footprint (base_link at its centre) in the world as ``(4, 2)`` CCW."""
    half_l, half_w = 0.5 * length_m, 0.5 * width_m
    local = np.array([[-half_l, -half_w], [half_l, -half_w], [half_l, half_w], [-half_l, half_w]])
    return pose.transform_points(local)


def separated(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether a separating axis exists between two convex polygons (touching counts as separated)."""
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
        pa, pb = a @ normals.T, b @ normals.T
        if np.any((pa.max(axis=0) <= pb.min(axis=0)) | (pb.max(axis=0) <= pa.min(axis=0))):
            return True
    return False


def _points_to_edges_distance(points: np.ndarray, poly: np.ndarray) -> float:
    starts = poly
    deltas = np.roll(poly, -1, axis=0) - poly
    rel = points[:, None, :] - starts[None, :, :]
    u = np.clip((rel * deltas[None]).sum(axis=2) / (deltas * deltas).sum(axis=1)[None], 0.0, 1.0)
    closest = starts[None] + u[..., None] * deltas[None]
    return float(np.sqrt(((points[:, None, :] - closest) ** 2).sum(axis=2)).min())


def polygon_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Distance between two convex polygons, 0 when they overlap."""
    if not separated(a, b):
        return 0.0
    return min(_points_to_edges_distance(a, b), _points_to_edges_distance(b, a))
