"""The simulator service's contract."""

from __future__ import annotations

from shared import topics
from shared.contracts.model import Contract, Flag, Request, Topic
from shared.contracts.services.common import CLOCK_QOS
from shared.endpoints import BLOCKING, RELIABLE, SENSOR_DATA, QoS
from shared.interfaces.simulator import SET_LOCALISATION, SIM_STATE, TELEPORT
from shared.messages import (
    CameraInfo,
    Clock,
    CollisionEvent,
    DockContact,
    DockInfraRed,
    Float64MultiArray,
    Image,
    LaserScan,
    Odometry,
    PacingHold,
    PoseStamped,
    Range,
    TFMessage,
    Twist,
)

CONTRACT = Contract(
    service="simulator",
    summary="The world (pymunk): a differential-drive robot, its sensors, the docks' contacts, the clock.",
    version="1.3",
    publishes=(
        Topic(topics.CLOCK, Clock, CLOCK_QOS, rate_hz=20.0, about="sim time: every other service's clock"),
        Topic(
            topics.ODOM,
            Odometry,
            RELIABLE,
            rate_hz=20.0,
            frame_id=topics.ODOM_FRAME,
            child_frame_id=topics.BASE_FRAME,
        ),
        Topic(
            topics.TF,
            TFMessage,
            RELIABLE,
            rate_hz=20.0,
            about="map -> odom (localisation) and odom -> base_link",
        ),
        Topic(topics.TF_STATIC, TFMessage, BLOCKING, rate_hz=1.0, about="the sensors' mounts on base_link"),
        Topic(
            topics.SCAN,
            LaserScan,
            SENSOR_DATA,
            rate_hz=10.0,
            frame_id=topics.LIDAR_FRAME,
            about="the lidar: glass is invisible to it",
        ),
        Topic(
            topics.ULTRASONIC,
            Range,
            SENSOR_DATA,
            rate_hz=20.0,
            frame_id=topics.ULTRASONIC_FRAME,
            about="the sonar: sees glass",
        ),
        Topic(
            topics.DOCK_CONTACT,
            DockContact,
            RELIABLE,
            rate_hz=20.0,
            frame_id=topics.MAP_FRAME,
            about="mated with a dock's contacts",
        ),
        Topic(
            topics.GROUND_TRUTH_POSE,
            PoseStamped,
            RELIABLE,
            rate_hz=20.0,
            frame_id=topics.MAP_FRAME,
            about="the truth, for judging runs",
        ),
        Topic(
            topics.COLLISIONS,
            CollisionEvent,
            BLOCKING,
            max_rate_hz=20.0,
            frame_id=topics.MAP_FRAME,
            about="each new contact with the world or a robot",
        ),
        Topic(
            topics.DETECTED_DOCK_POSE,
            PoseStamped,
            SENSOR_DATA,
            max_rate_hz=15.0,
            frame_id=topics.BASE_FRAME,
            about="with detection.source=synthetic: the true dock pose plus noise, while someone listens",
        ),
        Topic(
            topics.IR_DOCK,
            DockInfraRed,
            SENSOR_DATA,
            rate_hz=20.0,
            frame_id=topics.BASE_FRAME,
            when="while someone listens",
            about="the infrared receivers' near/far left/centre/right bits",
        ),
        Topic(
            topics.CAMERA_IMAGE,
            Image,
            SENSOR_DATA,
            rate_hz=15.0,
            frame_id=topics.CAMERA_OPTICAL_FRAME,
            when="with the camera enabled, while someone listens",
        ),
        Topic(
            topics.CAMERA_INFO,
            CameraInfo,
            SENSOR_DATA,
            rate_hz=15.0,
            frame_id=topics.CAMERA_OPTICAL_FRAME,
            when="with the camera enabled",
        ),
    ),
    subscribes=(
        Topic(
            topics.CMD_VEL,
            Twist,
            QoS(depth=1),
            about="the wheels' command; stops when it goes silent; while the robot moves, the world "
            "waits (briefly) for the command of each of its controller's ticks, known by the tick in the "
            "attachment, or by its arrival",
        ),
        Topic(
            topics.PACING_HOLD,
            PacingHold,
            QoS(depth=4),
            when="optional: pacing",
            about="a handoff between drivers, or a driver at work with its robot standing: the world waits "
            "until its holder lets go or, until_driven, a command that moves the robot answers the hold's "
            "tick or a later one; at most pacing.hold_wait_max_s of wall time while only holds are late",
        ),
        Topic(
            topics.POSE2D,
            Float64MultiArray,
            QoS(depth=1),
            when="optional: pacing",
            about="paces rtf: waits for late drivers",
        ),
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
