"""The docking service: takes the robot from anywhere in the room onto its charging dock.

Pure logic, no bus (each module unit-tested on its own):

- :mod:`~services.docking.approach` -- staging poses, waypoints and targets derived from a dock pose;
- :mod:`~services.docking.seed_controller` -- the baseline bang-bang line approach and the low-battery trigger;
- :mod:`~services.docking.graceful` -- the graceful (Park & Kuipers) docking controller;
- :mod:`~services.docking.pose_estimator` -- robot pose smoothing and latency compensation for the controller;
- :mod:`~services.docking.pose_filter` -- dock detection smoothing with timeout and outlier rejection;
- :mod:`~services.docking.dock_db` -- the dock database;
- :mod:`~services.docking.errors` -- result codes, feedback states and docking exceptions (Nav2's numbers);
- :mod:`~services.docking.kinematics` and :mod:`~services.docking.bench` -- a kinematic robot to test and
  compare controllers on;
- :mod:`~shared.pose_tracking` (from the kit) -- localisation carried forward by odometry, queryable at any time;
- :mod:`~services.docking.dock_tracker` -- detections placed in the map and filtered, per expected dock;
- :mod:`~services.docking.safety` -- lidar and sonar obstacle checks that excuse the dock;
- :mod:`~services.docking.approach_control` -- the two approach controllers behind one interface, backing off;
- :mod:`~services.docking.task_io`, :mod:`~services.docking.docking_run`, :mod:`~services.docking.undocking_run`,
  :mod:`~services.docking.patrol` -- the service's tasks as pure state machines;
- :mod:`~services.docking.drive_arbiter` -- one driver at a time (the service's cmd_vel or the planner);
- :mod:`~services.docking.mission` -- patrol, dock when low, resume when charged.

Wiring: :mod:`~services.docking.node` (``python -m services.docking``).
"""
