"""The battery service: a simulated battery that drains with the robot's motion and charges on the dock.

It publishes ``battery_status`` (sensor_msgs/BatteryState), integrates on the node's clock (sim time
when ``use_sim_time``), and answers ``battery/set_state`` so tests and demos can put the battery where
they need it. The model (:mod:`services.battery.model`) and the time keeping
(:mod:`services.battery.timekeeping`) are pure; :mod:`services.battery.node` wires them to the bus.
"""
