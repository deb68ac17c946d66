"""zendock's common kit: what every service, tool and test may use.

Each module is public and has one job; import what you need from it (``from shared.geometry import
Pose2D``). The package itself re-exports nothing on purpose: importing ``shared`` must stay free, so that
the pure modules (geometry, frames, world, messages) load without Zenoh and algorithm modules that use
them stay bus-free, as ``tests/unit/shared/test_kit_layers.py`` checks.

- bus: :mod:`shared.session` (open a session), :mod:`shared.node` (a node: publishers, subscriptions,
  timers, services; it re-exports the names of the three modules it is made of: :mod:`shared.executor`,
  the one place that runs callbacks one at a time, :mod:`shared.endpoints`, publishers, subscriptions,
  service servers and QoS, and :mod:`shared.encoding`, a sample's encoding and attachment),
  :mod:`shared.action` (actions), :mod:`shared.runtime` (a service's ``main``),
  :mod:`shared.parameter_server` (a node's parameters on the bus, ``zendock param``),
  :mod:`shared.navigation` (the navigation client), :mod:`shared.names` (key expressions, tokens).
- data: :mod:`shared.messages` and :mod:`shared.schema` (ROS-named message types), :mod:`shared.topics`,
  :mod:`shared.interfaces` (action and service types), :mod:`shared.world` (world files).
- pure helpers: :mod:`shared.parameters` (which parameters change at runtime, validated as at start-up),
  :mod:`shared.geometry` (SE(2)), :mod:`shared.frames` (frame names, sensor mounts, clock
  resets), :mod:`shared.ratelimit`, :mod:`shared.config_errors`, :mod:`shared.files`.
"""
