"""The planner's map server: the static map on ``map`` and behind ``map_server/map`` and ``load_map``.

Zenoh keeps no latched copy, so the map is published again every ``map_publish_period_s`` (wall clock)
and at once when it changes. ``load_map`` takes a map_server YAML path (``file://`` allowed) and answers
with the result codes of ``nav2_msgs/srv/LoadMap``; a new map is handed to the planner through
``on_map`` before it is published.
"""

from __future__ import annotations

import os.path
from collections.abc import Callable

from services.planner.map_messages import occupancy_grid_message
from services.planner.occupancy_map import OccupancyMap, load_map
from shared import topics
from shared.config_errors import ConfigError
from shared.interfaces.map_server import GET_MAP, GET_MAP_SERVICE, GetMapRequest, GetMapResponse
from shared.interfaces.navigation import LOAD_MAP, LOAD_MAP_SERVICE, LoadMapRequest, LoadMapResponse
from shared.messages import OccupancyGrid
from shared.node import RELIABLE, Node, ServiceError


class MapServer:
    """Serves and publishes the current static map; see the module docstring."""

    def __init__(self, node: Node, publish_period_s: float, on_map: Callable[[OccupancyMap], None]) -> None:
        self._node = node
        self._log = node.log
        self._on_map = on_map
        self._map_msg: OccupancyGrid | None = None
        self._map_pub = node.create_publisher(OccupancyGrid, topics.MAP, RELIABLE)
        node.create_service(LOAD_MAP, LOAD_MAP_SERVICE, self._on_load_map)
        node.create_service(GET_MAP, GET_MAP_SERVICE, self._on_get_map)
        self._timer = node.create_timer(publish_period_s, self.publish, wall=True)

    def set_map(self, occupancy: OccupancyMap, source: str) -> None:
        """Make ``occupancy`` (read from ``source``) the map: hand it over, then publish it."""
        self._on_map(occupancy)
        now = self._node.now()
        self._map_msg = occupancy_grid_message(occupancy, now, topics.MAP_FRAME, load_time_s=now)
        frame = occupancy.frame
        self._log.info(
            "map from %s: %d x %d cells at %g m, origin (%.2f, %.2f)",
            source,
            frame.width,
            frame.height,
            frame.resolution_m,
            frame.origin[0],
            frame.origin[1],
        )
        self.publish()

    def publish(self) -> None:
        if self._map_msg is not None:
            self._map_msg.header.stamp = self._node.now_msg()
            self._map_pub.publish(self._map_msg)

    def _on_get_map(self, request: GetMapRequest) -> GetMapResponse:
        if self._map_msg is None:
            raise ServiceError("no map loaded")
        return GetMapResponse(map=self._map_msg)

    def _on_load_map(self, request: LoadMapRequest) -> LoadMapResponse:
        url = request.map_url.strip().removeprefix("file://")
        if not url or not os.path.isfile(url):
            self._log.warning("load_map: no map file %r", request.map_url)
            return LoadMapResponse(result=LoadMapResponse.RESULT_MAP_DOES_NOT_EXIST)
        try:
            occupancy = load_map(url)
        except ConfigError as exc:
            self._log.warning("load_map: %s", exc)
            image_problem = "image" in str(exc) or "PGM" in str(exc)
            code = (
                LoadMapResponse.RESULT_INVALID_MAP_DATA
                if image_problem
                else LoadMapResponse.RESULT_INVALID_MAP_METADATA
            )
            return LoadMapResponse(result=code)
        self.set_map(occupancy, url)
        assert self._map_msg is not None
        return LoadMapResponse(map=self._map_msg, result=LoadMapResponse.RESULT_SUCCESS)
