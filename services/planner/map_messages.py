"""The planner's grids and paths as ROS message mirrors (nav_msgs OccupancyGrid and Path), and back.

Layouts follow nav_msgs: OccupancyGrid ``data`` is row-major from the origin cell (row 0 at the lowest
y), the same order as :class:`~services.planner.occupancy_map.OccupancyMap` keeps it, so conversion is a
ravel. Costmaps go out through nav2's cost-to-occupancy table for display.
"""

from __future__ import annotations

import numpy as np

from services.planner.costmap import CostGrid, occupancy_from_costs
from services.planner.grid_frame import GridFrame
from services.planner.occupancy_map import OccupancyMap
from shared.geometry import Pose2D
from shared.interfaces.costmap import Costmap, CostmapMetaData
from shared.messages import Header, MapMetaData, OccupancyGrid, Path, Pose, PoseStamped, Time


def _info(frame: GridFrame, load_time_s: float) -> MapMetaData:
    return MapMetaData(
        map_load_time=Time.from_sec(load_time_s),
        resolution=frame.resolution_m,
        width=frame.width,
        height=frame.height,
        origin=Pose.from_pose2d(Pose2D(*frame.origin)),
    )


def occupancy_grid_message(
    occupancy: OccupancyMap, stamp_s: float, frame_id: str, load_time_s: float | None = None
) -> OccupancyGrid:
    """An occupancy map as ``nav_msgs/OccupancyGrid`` (-1 unknown, 0..100)."""
    return OccupancyGrid(
        header=Header.at(stamp_s, frame_id),
        info=_info(occupancy.frame, stamp_s if load_time_s is None else load_time_s),
        data=np.ascontiguousarray(occupancy.data, dtype=np.int8).ravel(),
    )


def costmap_message(grid: CostGrid, stamp_s: float, frame_id: str) -> OccupancyGrid:
    """A costmap snapshot for display: nav2's translation of costs 0..255 to occupancy values."""
    return OccupancyGrid(
        header=Header.at(stamp_s, frame_id),
        info=_info(grid.frame, stamp_s),
        data=occupancy_from_costs(grid.costs).ravel(),
    )


def nav2_costmap_message(
    grid: CostGrid,
    stamp_s: float,
    frame_id: str,
    layer: str,
    window: tuple[float, float, float] | None = None,
) -> Costmap:
    """The costs as ``nav2_msgs/Costmap`` (Nav2's scale already): the whole grid, or the ``n x n`` cells
    (``n = side_m / resolution``, rounded) of the square ``window = (x, y, side_m)`` centred on a world point,
    cut to the grid (``side_m`` 0: an empty square with the grid's frame)."""
    frame, costs = grid.frame, grid.costs
    ix0, iy0, ix1, iy1 = 0, 0, frame.width, frame.height
    if window is not None:
        x, y, side_m = window
        n = int(round(side_m / frame.resolution_m))
        gx, gy = frame.world_to_grid(np.array([[x, y]]))[0]
        sx, sy = int(np.floor(gx - n / 2.0 + 0.5)), int(np.floor(gy - n / 2.0 + 0.5))
        ix0, iy0 = min(max(sx, 0), frame.width), min(max(sy, 0), frame.height)
        ix1, iy1 = min(max(sx + n, 0), frame.width), min(max(sy + n, 0), frame.height)
    ox, oy, yaw = frame.origin
    dx, dy = ix0 * frame.resolution_m, iy0 * frame.resolution_m
    origin = Pose2D(ox + dx * np.cos(yaw) - dy * np.sin(yaw), oy + dx * np.sin(yaw) + dy * np.cos(yaw), yaw)
    return Costmap(
        header=Header.at(stamp_s, frame_id),
        metadata=CostmapMetaData(
            map_load_time=Time.from_sec(stamp_s),
            update_time=Time.from_sec(stamp_s),
            layer=layer,
            resolution=frame.resolution_m,
            size_x=ix1 - ix0,
            size_y=iy1 - iy0,
            origin=Pose.from_pose2d(origin),
        ),
        data=np.ascontiguousarray(costs[iy0:iy1, ix0:ix1], dtype=np.uint8).ravel(),
    )


def occupancy_map_from_message(msg: OccupancyGrid) -> OccupancyMap:
    """Back from ``nav_msgs/OccupancyGrid``; raises ``ValueError`` when the sizes disagree."""
    width, height = int(msg.info.width), int(msg.info.height)
    data = np.asarray(msg.data, dtype=np.int8)
    if data.size != width * height:
        raise ValueError(f"occupancy grid has {data.size} cells for {width} x {height}")
    origin = msg.info.origin.to_pose2d()
    return OccupancyMap(
        resolution_m=msg.info.resolution,
        origin=(origin.x, origin.y, origin.yaw),
        data=data.reshape(height, width),
    )


def path_message(poses: np.ndarray, stamp_s: float, frame_id: str) -> Path:
    """``(N, 3)`` poses as ``nav_msgs/Path``, every pose stamped like the path."""
    header = Header.at(stamp_s, frame_id)
    return Path(
        header=header,
        poses=[
            PoseStamped(header, Pose.from_pose2d(Pose2D(float(x), float(y), float(yaw))))
            for x, y, yaw in np.asarray(poses, dtype=float).reshape(-1, 3)
        ],
    )
