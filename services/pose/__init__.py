"""The pose service: a tf buffer fed by ``tf`` and ``tf_static``, published as a 2-D pose.

It looks up ``map -> target_frame`` (default ``base_link``) at the latest common time and publishes
``map_to_base_link_pose2d`` (std_msgs/Float64MultiArray ``[x, y, yaw]``). The buffer
(:mod:`shared.tf_buffer`) is pure; :mod:`services.pose.node` wires it to the bus.
"""
