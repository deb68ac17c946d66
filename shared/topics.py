"""Topic, service and action names (relative: the node's namespace is prepended).

One place for the names keeps publishers and subscribers in different processes in agreement.
"""

CLOCK = "clock"
CMD_VEL = "cmd_vel"
ODOM = "odom"
TF = "tf"
TF_STATIC = "tf_static"
SCAN = "scan"
ULTRASONIC = "ultrasonic"
BATTERY_STATUS = "battery_status"
POSE2D = "map_to_base_link_pose2d"
#: The pose as Nav2's localiser publishes it (PoseWithCovarianceStamped in map), for Nav2 scripts.
AMCL_POSE = "amcl_pose"
DOCK_CONTACT = "dock_contact"
COLLISIONS = "collisions"
#: A handoff between two drivers of the robot: the world waits until it is driven again (see PacingHold).
PACING_HOLD = "pacing_hold"
GROUND_TRUTH_POSE = "ground_truth_pose"
DETECTED_DOCK_POSE = "detected_dock_pose"
DOCK_DETECTIONS = "dock_detections"
#: The robot's infrared receivers (Kobuki's DockInfraRed): which of the dock's beacon fields each sees.
IR_DOCK = "ir_dock"
CAMERA_IMAGE = "camera/image_raw"
CAMERA_INFO = "camera/camera_info"
ARUCO_DEBUG_IMAGE = "aruco/debug_image"
MAP = "map"
PLAN = "plan"

# Services (request/response over Zenoh queryables)
SIM_TELEPORT = "simulator/teleport"
SIM_STATE = "simulator/state"
SIM_SET_LOCALISATION = "simulator/set_localisation"
BATTERY_SET_STATE = "battery/set_state"
#: The fleet service's (in the fleet's namespace, not a robot's): ask for a dock, give it back.
FLEET_RESERVE_DOCK = "fleet/reserve_dock"
FLEET_RELEASE_DOCK = "fleet/release_dock"
#: ... and what it publishes: every dock's occupancy, the queue for docks.
FLEET_DOCKS = "fleet/docks"
FLEET_QUEUE = "fleet/queue"

# Actions (shared.action)
NAVIGATE_TO_POSE = "navigate_to_pose"
DOCK_ROBOT = "dock_robot"
UNDOCK_ROBOT = "undock_robot"
#: Nav2's bt_navigator and waypoint_follower: navigate_to_pose goals one after another.
NAVIGATE_THROUGH_POSES = "navigate_through_poses"
FOLLOW_WAYPOINTS = "follow_waypoints"
#: Served only to refuse it: zendock's worlds have no GPS.
FOLLOW_GPS_WAYPOINTS = "follow_gps_waypoints"
#: Nav2's controller_server: drive along a given path.
FOLLOW_PATH = "follow_path"
#: Nav2's planner_server: a path, without driving it.
COMPUTE_PATH_TO_POSE = "compute_path_to_pose"
COMPUTE_PATH_THROUGH_POSES = "compute_path_through_poses"
#: Nav2's smoother_server: a given path smoothed.
SMOOTH_PATH = "smooth_path"
#: Nav2's behaviours (the planner serves them): turn in place, reverse, drive straight, let time pass.
SPIN = "spin"
BACKUP = "backup"
DRIVE_ON_HEADING = "drive_on_heading"
WAIT = "wait"
#: Served only to refuse it with a reason (see docs/nav2-api.md).
ASSISTED_TELEOP = "assisted_teleop"

# Frames (REP 105)
MAP_FRAME = "map"
ODOM_FRAME = "odom"
BASE_FRAME = "base_link"
LIDAR_FRAME = "lidar_link"
ULTRASONIC_FRAME = "ultrasonic_link"
CAMERA_FRAME = "camera_link"
CAMERA_OPTICAL_FRAME = "camera_optical_frame"

# Counters a node adds to its stats (``@zendock/stats/<ns>/<node>``, under ``extra``)
#: The planner's sim seconds driven under a glass speed limit (all goals so far).
GLASS_SLOWED_STAT = "glass_slowed_s"
#: The metres the planner drove in those seconds (its pose track's speed): with the seconds, the time the
#: glass limit cost against driving them at full speed.
GLASS_SLOWED_M_STAT = "glass_slowed_m"
