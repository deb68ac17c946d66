"""The simulator service: physics of the robot in its room, and its sensors."""
