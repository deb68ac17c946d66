"""The docking service's contract."""

from __future__ import annotations

from shared import topics
from shared.contracts.model import Action, Contract, Flag, Request, Topic
from shared.contracts.services.common import DOCK_DATABASE, DOCKING_STATE, USE_SIM_TIME, lifecycle_requests
from shared.controllers import CONTROLLERS
from shared.endpoints import RELIABLE, SENSOR_DATA, QoS
from shared.interfaces.docking import DOCK_ROBOT, UNDOCK_ROBOT
from shared.interfaces.fleet import RELEASE_DOCK, RESERVE_DOCK
from shared.interfaces.navigation import (
    NAVIGATE_TO_POSE,
)
from shared.messages import (
    BatteryState,
    DockInfraRed,
    Float64MultiArray,
    LaserScan,
    Odometry,
    PacingHold,
    Path,
    PoseStamped,
    Range,
    String,
    TFMessage,
    Twist,
)

CONTRACT = Contract(
    service="docking",
    summary="Docking: on low battery or a dock_robot goal, navigate to the staging pose, approach, charge.",
    version="1.2",
    publishes=(
        Topic(
            topics.CMD_VEL,
            Twist,
            RELIABLE,
            max_rate_hz=20.0,
            when="while approaching or undocking",
            about="one command per control tick; its attachment carries the tick's sim time",
        ),
        Topic(DOCKING_STATE, String, RELIABLE, max_rate_hz=10.0, about="the phase in words, at each change"),
        Topic(
            topics.PACING_HOLD,
            PacingHold,
            RELIABLE,
            when="on sim time, at each handoff between it and the planner",
            about="hold the world from this tick until the planner moves the robot (until_driven) or the "
            "service lets go (hold false)",
        ),
    ),
    subscribes=(
        Topic(
            topics.BATTERY_STATUS, BatteryState, QoS(depth=5), about="the trigger (below 25 %) and CHARGING"
        ),
        Topic(topics.POSE2D, Float64MultiArray, QoS(depth=1)),
        Topic(topics.ODOM, Odometry, SENSOR_DATA),
        Topic(topics.SCAN, LaserScan, SENSOR_DATA, when="optional: holds the approach before an obstacle"),
        Topic(topics.ULTRASONIC, Range, SENSOR_DATA, when="optional: holds the approach before glass"),
        Topic(topics.TF_STATIC, TFMessage, QoS(depth=20), when="optional: the sensors' mounts for the above"),
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
    serves=lifecycle_requests("docking"),
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
