"""The perception service: ArUco markers in camera images become dock poses."""
