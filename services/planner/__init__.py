"""The planner service: map loading and rasterising, a layered costmap, A* with smoothing, and a
Regulated Pure Pursuit follower.

The modules here are pure algorithms over numpy (no Zenoh), besides the wiring: :mod:`.node` (the
action server and the goal's life), :mod:`.map_server` (the map on the bus) and the bus-free
:mod:`.costmap_updater` (sensor data into the layers) that the node drives.
"""
