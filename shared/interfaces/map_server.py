"""The map server's request for the current map, mirroring nav_msgs/srv/GetMap.

Zenoh pub/sub keeps no transient-local history, so a late joiner asks for the map with this request
(or waits for the planner's periodic republication on ``map``).
"""

from __future__ import annotations

from dataclasses import field

from shared.interface_types import ServiceType
from shared.messages import OccupancyGrid
from shared.schema import Message, message


@message("nav_msgs/srv/GetMap_Request")
class GetMapRequest(Message):
    pass


@message("nav_msgs/srv/GetMap_Response")
class GetMapResponse(Message):
    map: OccupancyGrid = field(default_factory=OccupancyGrid)


GET_MAP = ServiceType("nav_msgs/srv/GetMap", GetMapRequest, GetMapResponse)

#: Service name (relative to the namespace).
GET_MAP_SERVICE = "map_server/map"
#: The planner's inflated costmap, for display.
COSTMAP_TOPIC = "costmap"
