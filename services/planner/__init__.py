"""The planner service: map loading and rasterising, a layered costmap, A* with smoothing, and a
Regulated Pure Pursuit follower.

The modules here are pure algorithms over numpy (no Zenoh); the service's node wires them to keys.
"""
