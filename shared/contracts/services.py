"""Each zendock service's contract: the one place its endpoints, inputs and promised reactions are written.

The services declare what they declare; their nodes are held to these tables while they run
(:meth:`shared.contracts.model.Contract.check_endpoint`), ``zendock contract NAME`` prints them and
``zendock conform NAME -- COMMAND`` checks a program against them. Rates are of sim time at the defaults.
"""

from __future__ import annotations

from dataclasses import replace

from shared import topics
from shared.contracts.model import Action, Contract, Flag, Request, Topic
from shared.controllers import CONTROLLERS, DETECTORS
from shared.endpoints import BLOCKING, RELIABLE, SENSOR_DATA, QoS
from shared.interfaces.battery import SET_BATTERY_STATE
from shared.interfaces.costmap import (
    GET_COSTMAP,
    GLOBAL_COSTMAP_CLEAR,
    GLOBAL_COSTMAP_GET,
    LOCAL_COSTMAP_CLEAR,
    LOCAL_COSTMAP_GET,
)
from shared.interfaces.docking import DOCK_ROBOT, UNDOCK_ROBOT
from shared.interfaces.fleet import RELEASE_DOCK, RESERVE_DOCK, FleetDocks, FleetQueue
from shared.interfaces.lifecycle import GET_STATE
from shared.interfaces.map_server import COSTMAP_TOPIC, GET_MAP, GET_MAP_SERVICE
from shared.interfaces.navigation import (
    CLEAR_COSTMAPS_SERVICE,
    CLEAR_ENTIRE_COSTMAP,
    LOAD_MAP,
    LOAD_MAP_SERVICE,
    NAVIGATE_TO_POSE,
)
from shared.interfaces.simulator import SET_LOCALISATION, SIM_STATE, TELEPORT
from shared.messages import (
    BatteryState,
    CameraInfo,
    Clock,
    CollisionEvent,
    DockContact,
    DockDetection,
    DockInfraRed,
    Float64MultiArray,
    Image,
    LaserScan,
    OccupancyGrid,
    Odometry,
    Path,
    PoseStamped,
    PoseWithCovarianceStamped,
    Range,
    String,
    TFMessage,
    Twist,
)
from shared.nav2_stand_ins import get_state_service, stand_ins

#: The docking service's phase, in words (``docking/state``).
DOCKING_STATE = "docking/state"
#: Camera images: best effort, only the latest.
IMAGE_QOS = QoS(reliable=False, block=False, depth=1)
CLOCK_QOS = QoS(reliable=True, depth=1)
USE_SIM_TIME = Flag(
    "use_sim_time", "follow the simulator's clock on `clock` (zendock's stacks always set true)", needed=True
)


def _lifecycle(service: str) -> tuple[Request, ...]:
    """``<nav2 node>/get_state`` for each Nav2 node ``service`` stands in for (:mod:`shared.nav2_stand_ins`)."""
    return tuple(
        Request(
            get_state_service(name),
            GET_STATE,
            when="for Nav2 scripts (zendock's runtime serves it)",
            about=f"stands in for Nav2's {name}: `active` while the service runs",
        )
        for name in stand_ins(service)
    )


DOCK_DATABASE = Flag("dock_database", "the world file: its docks (pose, marker id, size) and staging offsets")

BATTERY = Contract(
    service="battery",
    summary="A simulated battery: drains with motion, charges while the robot is mated with a dock.",
    publishes=(
        Topic(
            topics.BATTERY_STATUS,
            BatteryState,
            RELIABLE,
            rate_hz=10.0,
            about="the charge; power_supply_status CHARGING (1) while mated, DISCHARGING (2) otherwise, FULL (4)",
        ),
    ),
    subscribes=(
        Topic(topics.ODOM, Odometry, SENSOR_DATA, rate_hz=20.0, about="the twist sets the motion load"),
        Topic(topics.DOCK_CONTACT, DockContact, QoS(depth=5), rate_hz=20.0, about="charging while `mated`"),
    ),
    serves=(
        Request(
            topics.BATTERY_SET_STATE,
            SET_BATTERY_STATE,
            about="set the charge and the drain/charge scales (NaN: leave as is); answers with the new state",
        ),
    ),
    flags=(
        USE_SIM_TIME,
        Flag("state_file", "keep the charge in this file across restarts"),
        Flag("drain_scale", "the charge drains this many times faster"),
        Flag("charge_scale", "the charge fills this many times faster"),
        Flag("publish_rate_hz", "battery_status this often (10 Hz), and at once on a change of status"),
    ),
    behaviour=(
        "answers set_state: battery_status shows the charge it set",
        "drains while the robot drives",
        "charges while mated: CHARGING and a rising charge with the robot on the dock",
    ),
    needs=("simulator",),
)

POSE = Contract(
    service="pose",
    summary="The robot's 2-D pose in the map, [x, y, yaw], from the tf tree (map -> odom -> base_link).",
    publishes=(
        Topic(
            topics.POSE2D,
            Float64MultiArray,
            RELIABLE,
            rate_hz=10.0,
            about="data = [x_m, y_m, yaw_rad] in the map frame",
        ),
        Topic(
            topics.AMCL_POSE,
            PoseWithCovarianceStamped,
            RELIABLE,
            when="for Nav2 scripts (zendock's pose service always)",
            about="the pose as Nav2's amcl_pose: on moving 0.25 m or turning 0.2 rad (as AMCL), and once a second",
        ),
    ),
    subscribes=(
        Topic(topics.TF, TFMessage, QoS(reliable=False, depth=100), rate_hz=20.0),
        Topic(topics.TF_STATIC, TFMessage, QoS(reliable=True, depth=20), rate_hz=1.0),
    ),
    serves=_lifecycle("pose"),
    flags=(USE_SIM_TIME,),
    behaviour=(
        "follows the robot: map_to_base_link_pose2d within 5 cm and 0.05 rad of the simulator's truth",
    ),
    needs=("simulator",),
)

SIMULATOR = Contract(
    service="simulator",
    summary="The world (pymunk): a differential-drive robot, its sensors, the docks' contacts, the clock.",
    publishes=(
        Topic(topics.CLOCK, Clock, CLOCK_QOS, rate_hz=20.0, about="sim time: every other service's clock"),
        Topic(topics.ODOM, Odometry, RELIABLE, rate_hz=20.0),
        Topic(
            topics.TF,
            TFMessage,
            RELIABLE,
            rate_hz=20.0,
            about="map -> odom (localisation) and odom -> base_link",
        ),
        Topic(topics.TF_STATIC, TFMessage, BLOCKING, rate_hz=1.0, about="the sensors' mounts on base_link"),
        Topic(topics.SCAN, LaserScan, SENSOR_DATA, rate_hz=10.0, about="the lidar: glass is invisible to it"),
        Topic(topics.ULTRASONIC, Range, SENSOR_DATA, rate_hz=20.0, about="the sonar: sees glass"),
        Topic(topics.DOCK_CONTACT, DockContact, RELIABLE, rate_hz=20.0, about="mated with a dock's contacts"),
        Topic(
            topics.GROUND_TRUTH_POSE, PoseStamped, RELIABLE, rate_hz=20.0, about="the truth, for judging runs"
        ),
        Topic(
            topics.COLLISIONS, CollisionEvent, BLOCKING, about="each new contact with the world or a robot"
        ),
        Topic(
            topics.DETECTED_DOCK_POSE,
            PoseStamped,
            SENSOR_DATA,
            about="with detection.source=synthetic: the true dock pose plus noise, while someone listens",
        ),
        Topic(
            topics.IR_DOCK,
            DockInfraRed,
            SENSOR_DATA,
            rate_hz=20.0,
            when="while someone listens",
            about="the infrared receivers' near/far left/centre/right bits",
        ),
        Topic(
            topics.CAMERA_IMAGE,
            Image,
            SENSOR_DATA,
            rate_hz=15.0,
            when="with the camera enabled, while someone listens",
        ),
        Topic(topics.CAMERA_INFO, CameraInfo, SENSOR_DATA, rate_hz=15.0, when="with the camera enabled"),
    ),
    subscribes=(
        Topic(topics.CMD_VEL, Twist, QoS(depth=1), about="the wheels' command; stops when it goes silent"),
        Topic(topics.POSE2D, Float64MultiArray, QoS(depth=1), about="paces rtf: waits for late drivers"),
    ),
    serves=(
        Request(topics.SIM_TELEPORT, TELEPORT, about="place the robot"),
        Request(topics.SIM_STATE, SIM_STATE, about="the truth and counters"),
        Request(topics.SIM_SET_LOCALISATION, SET_LOCALISATION, about="set the map -> odom error"),
    ),
    flags=(
        Flag("world", "the world file (as --world)", needed=True),
        Flag("rtf", "real-time factor, or max"),
        Flag("seed", "noise seed"),
        Flag("robots", "robot namespaces served"),
        Flag("localisation.error", "[x_m, y_m, yaw_rad] map -> odom error"),
        Flag("detection.source", "aruco (camera images) or synthetic (noisy truth)"),
    ),
    behaviour=(
        "keeps the clock: sim time advances",
        "drives: odom shows motion after cmd_vel",
        "answers teleport: ground_truth_pose moves to the asked pose",
    ),
)

PLANNER = Contract(
    service="planner",
    summary="Navigation (Nav2's role): the map, a costmap with glass from the sonar, A*, a path follower.",
    publishes=(
        Topic(topics.CMD_VEL, Twist, RELIABLE, when="while navigating", about="drives toward the goal"),
        Topic(topics.PLAN, Path, RELIABLE, about="the global plan, at each (re)plan"),
        Topic(topics.MAP, OccupancyGrid, RELIABLE, about="the static map, on start and on load_map"),
        Topic(
            COSTMAP_TOPIC, OccupancyGrid, QoS(reliable=False, depth=1), about="the costmap with glass marks"
        ),
    ),
    subscribes=(
        Topic(topics.POSE2D, Float64MultiArray, QoS(depth=1), rate_hz=10.0),
        Topic(topics.ODOM, Odometry, QoS(depth=5), rate_hz=20.0),
        Topic(topics.SCAN, LaserScan, SENSOR_DATA, rate_hz=10.0),
        Topic(topics.ULTRASONIC, Range, SENSOR_DATA, rate_hz=20.0),
        Topic(topics.TF_STATIC, TFMessage, QoS(depth=5)),
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
        *_lifecycle("planner"),
    ),
    serves_actions=(
        Action(
            topics.NAVIGATE_TO_POSE,
            NAVIGATE_TO_POSE,
            about="one goal at a time: a new goal preempts the active one (CANCELED)",
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

DOCKING = Contract(
    service="docking",
    summary="Docking: on low battery or a dock_robot goal, navigate to the staging pose, approach, charge.",
    publishes=(
        Topic(topics.CMD_VEL, Twist, RELIABLE, when="while approaching or undocking"),
        Topic(DOCKING_STATE, String, RELIABLE, about="the phase in words, at each change"),
    ),
    subscribes=(
        Topic(
            topics.BATTERY_STATUS, BatteryState, QoS(depth=5), about="the trigger (below 25 %) and CHARGING"
        ),
        Topic(topics.POSE2D, Float64MultiArray, QoS(depth=1)),
        Topic(topics.ODOM, Odometry, SENSOR_DATA),
        Topic(topics.SCAN, LaserScan, SENSOR_DATA),
        Topic(topics.ULTRASONIC, Range, SENSOR_DATA),
        Topic(topics.TF_STATIC, TFMessage, QoS(depth=20)),
        Topic(topics.DETECTED_DOCK_POSE, PoseStamped, SENSOR_DATA, when="while it wants dock detections"),
        Topic(topics.IR_DOCK, DockInfraRed, SENSOR_DATA, when="with controller=ir"),
        Topic(
            topics.POSE2D,
            Float64MultiArray,
            QoS(depth=20),
            when="with fleet=true",
            fleet_wide=True,
            about="the other robots' poses (*/map_to_base_link_pose2d)",
        ),
        Topic(topics.BATTERY_STATUS, BatteryState, QoS(depth=20), when="with fleet=true", fleet_wide=True),
        Topic(DOCKING_STATE, String, QoS(depth=20), when="with fleet=true", fleet_wide=True),
        Topic(topics.PLAN, Path, QoS(depth=20), when="with fleet=true", fleet_wide=True),
    ),
    calls=(
        Request(topics.FLEET_RESERVE_DOCK, RESERVE_DOCK, when="with fleet=true"),
        Request(topics.FLEET_RELEASE_DOCK, RELEASE_DOCK, when="with fleet=true"),
    ),
    serves=_lifecycle("docking"),
    serves_actions=(
        Action(topics.DOCK_ROBOT, DOCK_ROBOT, about="dock at dock_id (or the nearest dock)"),
        Action(topics.UNDOCK_ROBOT, UNDOCK_ROBOT, about="back off the dock to the staging pose"),
    ),
    uses_actions=(Action(topics.NAVIGATE_TO_POSE, NAVIGATE_TO_POSE, about="to the staging pose"),),
    flags=(
        USE_SIM_TIME,
        DOCK_DATABASE,
        Flag("controller", "zendock's own approach laws: " + ", ".join(CONTROLLERS)),
        Flag("fleet", "share docks through the fleet service"),
        Flag("resume_at", "undock at this charge (fleet)"),
    ),
    behaviour=(
        "docks: a dock_robot goal from 1.5 m in front of the dock gets feedback and a successful result, "
        "and battery_status says CHARGING (or FULL, when the charge was nearly full)",
    ),
    needs=("simulator", "battery", "pose", "planner"),
)

PERCEPTION = Contract(
    service="perception",
    summary="The dock from pixels: ArUco markers in camera images become detected_dock_pose.",
    publishes=(
        Topic(
            topics.DETECTED_DOCK_POSE,
            PoseStamped,
            SENSOR_DATA,
            about="the dock in base_link, from pixels alone",
        ),
        Topic(topics.DOCK_DETECTIONS, DockDetection, RELIABLE, about="each detection with its quality"),
        Topic(
            topics.ARUCO_DEBUG_IMAGE,
            Image,
            IMAGE_QOS,
            when="optional: a view for people",
            about="the image with the markers drawn, while someone listens",
        ),
    ),
    subscribes=(
        Topic(
            topics.CAMERA_INFO,
            CameraInfo,
            QoS(reliable=False, depth=1),
            about="the latest only; best effort, as the camera sends it",
        ),
        Topic(topics.TF_STATIC, TFMessage, QoS(depth=20)),
        Topic(topics.CAMERA_IMAGE, Image, IMAGE_QOS, when="while someone listens to its detections"),
    ),
    flags=(
        DOCK_DATABASE,
        Flag("dock_detector", " or ".join(DETECTORS) + " (without a camera it stays idle)"),
    ),
    behaviour=(
        "sees the dock: with the robot 1 m in front of the dock, detected_dock_pose within 5 cm of the truth",
    ),
    needs=("simulator",),
)

VIZ = Contract(
    service="viz",
    summary="A Foxglove WebSocket view of the robot(s): map, costmap, scans, sonar, plan, battery, poses.",
    subscribes=(
        Topic(topics.BATTERY_STATUS, BatteryState, QoS(depth=5)),
        Topic(topics.COLLISIONS, CollisionEvent, QoS(depth=5)),
        Topic(COSTMAP_TOPIC, OccupancyGrid, SENSOR_DATA),
        Topic(topics.DETECTED_DOCK_POSE, PoseStamped, SENSOR_DATA),
        Topic(topics.DOCK_CONTACT, DockContact, QoS(depth=5)),
        Topic(topics.GROUND_TRUTH_POSE, PoseStamped, QoS(depth=5)),
        Topic(topics.MAP, OccupancyGrid, QoS(depth=1)),
        Topic(topics.POSE2D, Float64MultiArray, QoS(depth=5)),
        Topic(topics.PLAN, Path, QoS(depth=5)),
        Topic(topics.SCAN, LaserScan, SENSOR_DATA),
        Topic(topics.TF, TFMessage, QoS(depth=5)),
        Topic(topics.TF_STATIC, TFMessage, QoS(depth=5)),
        Topic(topics.ULTRASONIC, Range, SENSOR_DATA),
        Topic(topics.CAMERA_IMAGE, Image, IMAGE_QOS, when="while a viewer watches it"),
        Topic(topics.ARUCO_DEBUG_IMAGE, Image, IMAGE_QOS, when="while a viewer watches it"),
    ),
    calls=(Request(GET_MAP_SERVICE, GET_MAP, about="the map, once, if none arrived"),),
    flags=(Flag("world", "the world file to draw (as --world)"), Flag("port", "WebSocket port (loopback)")),
    notes=(
        "Its behaviour is a WebSocket server for viewers, outside the bus; conform checks its endpoints only.",
    ),
)

FLEET = Contract(
    service="fleet",
    summary="Shares docks between robots: reservations with leases, a queue, the docks' occupancy.",
    publishes=(
        Topic(topics.FLEET_DOCKS, FleetDocks, BLOCKING, rate_hz=1.0, about="every dock's occupancy"),
        Topic(topics.FLEET_QUEUE, FleetQueue, BLOCKING, rate_hz=1.0, about="robots waiting for a dock"),
    ),
    serves=(
        Request(topics.FLEET_RESERVE_DOCK, RESERVE_DOCK, about="a dock for a robot, or a place in the queue"),
        Request(topics.FLEET_RELEASE_DOCK, RELEASE_DOCK, about="give the dock back"),
    ),
    flags=(Flag("world", "the world file whose docks are shared", needed=True),),
    behaviour=("reserves and releases: a robot gets a dock, fleet/docks shows it taken, then free again",),
)

ROS2_BRIDGE = Contract(
    service="ros2_bridge",
    summary="zendock seen from ROS 2 (rmw_zenoh): nodes, topics, actions, forwarded only while wanted.",
    publishes=(
        Topic(topics.CMD_VEL, Twist, RELIABLE, about="from ROS 2's /cmd_vel (Twist or TwistStamped)"),
    ),
    uses_actions=(
        Action(topics.NAVIGATE_TO_POSE, NAVIGATE_TO_POSE),
        Action(topics.DOCK_ROBOT, DOCK_ROBOT),
        Action(topics.UNDOCK_ROBOT, UNDOCK_ROBOT),
    ),
    subscribes_on_demand=True,
    flags=(Flag("domain_id", "the ROS_DOMAIN_ID of its rmw_zenoh face", needed=True),),
    behaviour=("shows zendock to ROS 2: an rmw_zenoh node token for each zendock service",),
    needs=("simulator",),
    notes=("It subscribes to a robot's topics only while a ROS 2 subscriber wants them.",),
)

#: The same promise on DDS (real rclpy): the same routes (shared/ros2/bridge_routes.py), another middleware.
ROS2_DDS = replace(
    ROS2_BRIDGE,
    service="ros2_dds",
    summary="zendock seen from ROS 2 on DDS (real rclpy, Fast DDS): nodes, topics, actions, forwarded only while wanted.",
    flags=(Flag("domain_id", "the ROS_DOMAIN_ID of its rclpy (DDS) face", needed=True),),
    behaviour=("shows zendock to ROS 2 on DDS: an rclpy node for each zendock service that is up",),
    notes=(
        "It subscribes to a robot's topics only while a ROS 2 subscriber matches (transient-local ones "
        "always), and runs from .venv-ros2 (make ros2).",
    ),
)

CONTRACTS: dict[str, Contract] = {
    c.service: c
    for c in (BATTERY, DOCKING, FLEET, PERCEPTION, PLANNER, POSE, ROS2_BRIDGE, ROS2_DDS, SIMULATOR, VIZ)
}


def contract_for(service: str) -> Contract | None:
    """The contract of zendock's service ``service`` (its node name), or ``None``."""
    return CONTRACTS.get(service)
