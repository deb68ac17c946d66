"""Does the lidar already explain a sonar echo? Then the echo is not glass and must not mark the costmap.

A sonar reports the nearest echo anywhere in its cone, and the range layer marks the whole arc at that
range. Looking down a one-metre corridor, the cone's edges meet the side walls about two metres out,
so the arc lands across the corridor and blocks it. The range layer is there to add what the lidar
cannot see (glass), so an echo is "explained" when the lidar has a hit inside the cone (widened by
``margin_rad``: a real sonar beam has no sharp edge, and lidar beams sample a grazing wall sparsely)
no further than the echo plus ``tolerance_m``. Such an echo only clears the cone short of it; an
unexplained one (glass: the lidar's light went through) marks the arc as before.
"""

from __future__ import annotations

import math

import numpy as np

#: Widen the cone by this much on each side when looking for lidar hits: about two of the lidar's 1-degree
#: beams, so that a wall at the cone's edge is found between two beams. It was 0.1 rad, and a wall or a box
#: in that wider band "explained" the echo of a pane's end standing nearer, inside the cone, in the gap
#: beside them: the end was cleared as floor (measurement 121's collisions). With the simulator's own
#: sensors over the 100 generated glass rooms, 0.1 -> 0.03 took the glass echoes explained away from 7.4 %
#: to 2.9 % at poses along a wall or a box, and from 3.6 % to 2.1 % at random poses, while the wall and box
#: echoes left unexplained (false glass) stayed at 0.03-0.07 %; at 0.01 they rose to 0.26 % (measurement
#: 140).
CONE_MARGIN_RAD = 0.03
#: A lidar hit this much beyond the echo still explains it (noise, and a grazing wall's sparse hits).
ECHO_TOLERANCE_M = 0.1


def echo_explained_by_lidar(
    sonar_pose: tuple[float, float, float],
    range_m: float,
    field_of_view_rad: float,
    lidar_hits_xy: np.ndarray | None,
    margin_rad: float = CONE_MARGIN_RAD,
    tolerance_m: float = ECHO_TOLERANCE_M,
) -> bool:
    """Whether a lidar hit (map frame, ``(N, 2)``) inside the widened cone lies no further than the echo."""
    if lidar_hits_xy is None or len(lidar_hits_xy) == 0 or not math.isfinite(range_m):
        return False
    x, y, yaw = sonar_pose
    dx = lidar_hits_xy[:, 0] - x
    dy = lidar_hits_xy[:, 1] - y
    distance = np.hypot(dx, dy)
    bearing = np.abs((np.arctan2(dy, dx) - yaw + math.pi) % (2.0 * math.pi) - math.pi)
    in_cone = bearing <= 0.5 * field_of_view_rad + margin_rad
    return bool(np.any(in_cone & (distance <= range_m + tolerance_m)))
