"""The planner service's contract."""

from __future__ import annotations

from shared import topics
from shared.contracts.model import Action, Contract, Flag, Request, Topic
from shared.contracts.services.common import USE_SIM_TIME, lifecycle_requests
from shared.endpoints import RELIABLE, SENSOR_DATA, QoS
from shared.interfaces.behaviors import ASSISTED_TELEOP, BACK_UP, DRIVE_ON_HEADING, SPIN, WAIT
from shared.interfaces.costmap import (
    GET_COSTMAP,
    GLOBAL_COSTMAP_CLEAR,
    GLOBAL_COSTMAP_GET,
    LOCAL_COSTMAP_CLEAR,
    LOCAL_COSTMAP_GET,
    REGION_CLEARS,
    region_clear_service,
)
from shared.interfaces.map_server import COSTMAP_TOPIC, GET_MAP, GET_MAP_SERVICE
from shared.interfaces.navigation import (
    CLEAR_COSTMAPS_SERVICE,
    CLEAR_ENTIRE_COSTMAP,
    COMPUTE_PATH_THROUGH_POSES,
    COMPUTE_PATH_TO_POSE,
    FOLLOW_GPS_WAYPOINTS,
    FOLLOW_PATH,
    FOLLOW_WAYPOINTS,
    LOAD_MAP,
    LOAD_MAP_SERVICE,
    NAVIGATE_THROUGH_POSES,
    NAVIGATE_TO_POSE,
    SMOOTH_PATH,
)
from shared.messages import (
    Float64MultiArray,
    LaserScan,
    OccupancyGrid,
    Odometry,
    PacingHold,
    Path,
    Range,
    TFMessage,
    Twist,
)

CONTRACT = Contract(
    service="planner",
    summary="Navigation (Nav2's role): the map, a costmap with glass from the sonar, A*, a path follower.",
    version="1.2",
    publishes=(
        Topic(
            topics.CMD_VEL,
            Twist,
            RELIABLE,
            max_rate_hz=20.0,
            when="while navigating",
            about="drives toward the goal, one command per control tick; its attachment carries the "
            "tick's sim time",
        ),
        Topic(
            topics.PACING_HOLD,
            PacingHold,
            RELIABLE,
            when="on sim time, while it works with its robot standing: a plan after a stop, the way "
            "through suspected glass, glass put back, a clearing",
            about="hold the world from this tick until the planner lets go (hold false; until_driven false)",
        ),
        Topic(
            topics.PLAN,
            Path,
            RELIABLE,
            max_rate_hz=5.0,
            frame_id=topics.MAP_FRAME,
            about="the global plan, at each (re)plan",
        ),
        Topic(
            topics.MAP,
            OccupancyGrid,
            RELIABLE,
            max_rate_hz=1.0,
            frame_id=topics.MAP_FRAME,
            about="the static map, on start and on load_map",
        ),
        Topic(
            COSTMAP_TOPIC,
            OccupancyGrid,
            QoS(reliable=False, depth=1),
            max_rate_hz=5.0,
            frame_id=topics.MAP_FRAME,
            about="the costmap with glass marks",
        ),
    ),
    subscribes=(
        Topic(topics.POSE2D, Float64MultiArray, QoS(depth=1), rate_hz=10.0),
        Topic(topics.ODOM, Odometry, QoS(depth=5), rate_hz=20.0),
        Topic(topics.SCAN, LaserScan, SENSOR_DATA, rate_hz=10.0),
        Topic(topics.ULTRASONIC, Range, SENSOR_DATA, rate_hz=20.0),
        Topic(
            topics.TF_STATIC,
            TFMessage,
            QoS(depth=5),
            when="optional: the sensors' mounts (zendock's robot's by default)",
        ),
    ),
    serves=(
        Request(CLEAR_COSTMAPS_SERVICE, CLEAR_ENTIRE_COSTMAP),
        Request(LOAD_MAP_SERVICE, LOAD_MAP),
        Request(GET_MAP_SERVICE, GET_MAP),
        Request(
            GLOBAL_COSTMAP_GET, GET_COSTMAP, about="the whole costmap, Nav2's costs (0 free .. 254 lethal)"
        ),
        Request(LOCAL_COSTMAP_GET, GET_COSTMAP, about="the square of local_costmap_size_m round the robot"),
        Request(
            GLOBAL_COSTMAP_CLEAR,
            CLEAR_ENTIRE_COSTMAP,
            about="forget the lidar's marks and all the glass the sonar heard",
        ),
        Request(
            LOCAL_COSTMAP_CLEAR,
            CLEAR_ENTIRE_COSTMAP,
            about="forget the lidar's marks and the glass round the robot",
        ),
        *(
            Request(
                region_clear_service(costmap, what),
                srv,
                about={
                    "except_region": "forget the lidar's marks and the glass memory outside the square of side "
                    "reset_distance round the robot",
                    "around_robot": "forget the lidar's marks and the glass memory inside the square of side "
                    "reset_distance round the robot",
                    "around_pose": "forget the lidar's marks and the glass memory inside the square of side "
                    "reset_distance round the pose (in map)",
                }[what],
            )
            for costmap in ("global", "local")
            for what, srv in REGION_CLEARS
        ),
        *lifecycle_requests("planner"),
    ),
    uses_actions=(
        Action(
            topics.NAVIGATE_TO_POSE,
            NAVIGATE_TO_POSE,
            about="its own, for follow_waypoints and navigate_through_poses: one goal a pose",
        ),
    ),
    serves_actions=(
        Action(
            topics.NAVIGATE_TO_POSE,
            NAVIGATE_TO_POSE,
            about="one goal at a time: a new goal preempts the active one (CANCELED)",
        ),
        Action(
            topics.NAVIGATE_THROUGH_POSES,
            NAVIGATE_THROUGH_POSES,
            about="navigate_to_pose to each pose in turn; a failed leg ends it with that leg's code",
        ),
        Action(
            topics.FOLLOW_WAYPOINTS,
            FOLLOW_WAYPOINTS,
            about="navigate_to_pose to each waypoint in turn; one it cannot reach is in missed_waypoints",
        ),
        Action(
            topics.FOLLOW_GPS_WAYPOINTS,
            FOLLOW_GPS_WAYPOINTS,
            about="not served (no GPS in zendock's worlds): every goal ends at once, ABORTED with the reason",
        ),
        Action(
            topics.COMPUTE_PATH_TO_POSE,
            COMPUTE_PATH_TO_POSE,
            about="a path from the robot (or start) to the goal, not driven; Nav2's 200s on failure",
        ),
        Action(
            topics.COMPUTE_PATH_THROUGH_POSES,
            COMPUTE_PATH_THROUGH_POSES,
            about="a path through the goals in order, leg by leg, not driven; Nav2's 300s on failure",
        ),
        Action(
            topics.SMOOTH_PATH,
            SMOOTH_PATH,
            about="a given path shortcut and smoothed within the costmap's costs; Nav2's 500s on failure",
        ),
        Action(
            topics.FOLLOW_PATH,
            FOLLOW_PATH,
            about="drive a given path with navigation's controller, no replanning; Nav2's 100s on failure",
        ),
        Action(topics.SPIN, SPIN, about="turn in place by target_yaw (rad); stops short of an obstacle"),
        Action(topics.BACKUP, BACK_UP, about="reverse target.x (m) at speed; stops short of an obstacle"),
        Action(
            topics.DRIVE_ON_HEADING,
            DRIVE_ON_HEADING,
            about="drive target.x (m) straight at speed (same sign); stops short of an obstacle",
        ),
        Action(topics.WAIT, WAIT, about="let time pass; sends no command"),
        Action(
            topics.ASSISTED_TELEOP,
            ASSISTED_TELEOP,
            about="not served: every goal ends at once, ABORTED with the reason",
        ),
    ),
    flags=(
        USE_SIM_TIME,
        Flag("map_yaml", "the occupancy map (zendock map save)", needed=True),
        Flag("glass_memory_file", "keep the glass marks across restarts"),
        Flag("max_linear_vel_mps", "speed limit"),
        Flag("costmap_update_rate_hz", "sensor folding rate"),
    ),
    behaviour=(
        "navigates: a navigate_to_pose goal 1 m away gets feedback and SUCCEEDED, the robot within 25 cm of it",
    ),
    needs=("simulator", "pose"),
)
