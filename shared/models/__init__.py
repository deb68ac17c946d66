"""Models of the robot's world that more than one service runs: no bus, only numbers.

The simulator publishes what these models say (the dock's infrared beacon, the contacts' mating, ray
casts against the room's walls, the robot's footprint), and the docking service's infrared bench
(:mod:`services.docking.ir_bench`) closes its control loop on the same models, so the two cannot drift
apart. Services meet only on the bus; what both must compute the same way lives here.
"""
