"""What the simulator publishes for each robot, as a table: topic, type, QoS, rate, how, on demand or not.

Each step :meth:`Channels.publish_due` walks the table once per robot, in the table's order, publishing
the channels whose sim-time schedule is due. Every schedule advances every step, whether or not a robot
has a subscriber, so a channel's phase never depends on who listens.

The clock comes LAST for each robot: a sim-time timer it wakes then acts on this step's odometry, tf and
sensors, which went out before it on the same link, not on the step before. The table is built in that
order and :func:`channel_table` asserts it.

Collision events are not here: they are published when the physics reports them, not on a schedule.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from services.simulator.camera import CameraRenderer, Motion
from services.simulator.camera_frames import camera_info, camera_mount_transforms
from services.simulator.pacing import CommandCadence, HandoffHold
from services.simulator.params import Params
from services.simulator.physics import Robot
from shared import topics
from shared.controllers import DETECTORS
from shared.geometry import Pose2D
from shared.messages import (
    CameraInfo,
    Clock,
    DockContact,
    DockInfraRed,
    Header,
    Image,
    LaserScan,
    Odometry,
    Pose,
    PoseStamped,
    PoseWithCovariance,
    Range,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
    Twist,
    TwistWithCovariance,
)
from shared.node import BLOCKING, RELIABLE, SENSOR_DATA, Publisher, QoS

#: The clock's QoS: reliable, and only the newest tick matters.
CLOCK_QOS = QoS(reliable=True, depth=1)


@dataclass
class SimRobot:
    """One simulated robot: its physics, its publishers (by topic) and what it was last told."""

    namespace: str
    sim: Robot
    prefix: str
    pubs: dict[str, Publisher[Any]] = field(default_factory=dict)
    cmd_v: float = 0.0
    cmd_w: float = 0.0
    #: Sim time the last command arrived (the cmd_vel watchdog's clock).
    last_cmd_s: float = -math.inf
    #: Sim time of the control tick the last command answers (from its attachment), else its arrival: how
    #: far behind the world the robot's driver is, which lockstep holds the world to.
    answered_s: float = -math.inf
    #: The cadence of its commands: its controller's period, which lockstep holds the world to.
    cadence: CommandCadence = field(default_factory=CommandCadence)
    #: A handoff between its drivers the world waits through (see PacingHold).
    handoff: HandoffHold = field(default_factory=HandoffHold)
    #: Sim time of the last map_to_base_link_pose2d (the localisation the controllers steer on).
    last_pose_s: float = -math.inf
    watchdog_tripped: bool = True
    pending_detections: deque[tuple[float, PoseStamped]] = field(default_factory=deque)
    collisions_total: int = 0
    camera: CameraRenderer | None = None
    frames_rendered: int = 0

    def topic(self, name: str) -> str:
        return f"{self.prefix}{name}"


@dataclass
class Every:
    """Fires every ``period_s`` of sim time."""

    period_s: float
    next_s: float = 0.0

    def due(self, now_s: float) -> bool:
        if now_s + 1e-9 < self.next_s:
            return False
        self.next_s = max(self.next_s + self.period_s, now_s + self.period_s * 0.5)
        return True


#: Publish (or queue) one channel for one robot: ``(robot, publisher, sim_now_s, stamp)``.
PublishFn = Callable[[SimRobot, Publisher[Any], float, Time], None]


@dataclass(frozen=True)
class Channel:
    """One row of the table. ``rate_hz`` None: every step. ``on_demand``: only while subscribed.

    Two rows may share a topic (the synthetic detector queues at its rate, the queue drains every step).
    """

    topic: str
    msg_type: type
    qos: QoS
    rate_hz: float | None
    publish: PublishFn
    on_demand: bool = False


def tf_message(robot: SimRobot, now: float) -> TFMessage:
    """map -> odom (the simulated localiser) and odom -> base_link (odometry), stamped ``now``."""
    stamp = Time.from_sec(now)
    return TFMessage(
        [
            TransformStamped(
                Header(stamp, topics.MAP_FRAME),
                topics.ODOM_FRAME,
                Transform.from_pose2d(robot.sim.map_to_odom()),
            ),
            TransformStamped(
                Header(stamp, topics.ODOM_FRAME),
                topics.BASE_FRAME,
                Transform.from_pose2d(robot.sim.odom_pose),
            ),
        ]
    )


def contact_message(robot: SimRobot, now: float) -> DockContact:
    c = robot.sim.dock_contact()
    finite = [
        v if v is not None and math.isfinite(v) else 0.0
        for v in (c.lateral_error_m, c.yaw_error_rad, c.along_error_m)
    ]
    return DockContact(
        Header.at(now, topics.MAP_FRAME), c.dock_id or "", bool(c.mated), bool(c.touching), *finite
    )


def channel_table(params: Params) -> list[Channel]:
    """The channels a simulator with ``params`` publishes, in publishing order (the clock last)."""
    camera_params = params.camera
    info = camera_info(camera_params)
    scan_period_s = 1.0 / params.lidar.rate_hz

    def tf_static(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        p = robot.sim.params
        mounts = [
            (topics.LIDAR_FRAME, Pose2D(p.lidar.mount_x_m, p.lidar.mount_y_m, 0.0)),
            (topics.ULTRASONIC_FRAME, Pose2D(p.ultrasonic.mount_x_m, 0.0, 0.0)),
        ]
        transforms = [
            TransformStamped(Header(stamp, topics.BASE_FRAME), child, Transform.from_pose2d(mount))
            for child, mount in mounts
        ]
        pub.publish(TFMessage(transforms + camera_mount_transforms(camera_params, stamp)))

    def tf(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        pub.publish(tf_message(robot, now))

    def odom(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        twist = robot.sim.twist
        pub.publish(
            Odometry(
                Header(stamp, topics.ODOM_FRAME),
                topics.BASE_FRAME,
                PoseWithCovariance(Pose.from_pose2d(robot.sim.odom_pose)),
                TwistWithCovariance(Twist.planar(twist.linear_mps, twist.angular_radps)),
            )
        )

    def scan(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        s = robot.sim.lidar_scan()
        n = len(s.ranges_m)
        pub.publish(
            LaserScan(
                header=Header(stamp, topics.LIDAR_FRAME),
                angle_min=s.angle_min_rad,
                angle_max=s.angle_min_rad + s.angle_increment_rad * (n - 1),
                angle_increment=s.angle_increment_rad,
                time_increment=0.0,
                scan_time=scan_period_s,
                range_min=s.range_min_m,
                range_max=s.range_max_m,
                ranges=np.asarray(s.ranges_m, dtype=np.float32),
                intensities=np.zeros(0, dtype=np.float32),
            )
        )

    def ultrasonic(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        p = robot.sim.params.ultrasonic
        pub.publish(
            Range(
                header=Header(stamp, topics.ULTRASONIC_FRAME),
                radiation_type=Range.ULTRASOUND,
                field_of_view=p.field_of_view_rad,
                min_range=p.range_min_m,
                max_range=p.range_max_m,
                range=float(robot.sim.ultrasonic_range()),
            )
        )

    def capture_detection(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        detection = robot.sim.detect_dock()
        if detection is not None:
            msg = PoseStamped(
                Header.at(now, topics.BASE_FRAME), Pose.from_pose2d(detection.dock_pose_in_base)
            )
            robot.pending_detections.append((now + params.detection.latency_s, msg))

    def release_detections(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        queue = robot.pending_detections
        while queue and queue[0][0] <= now + 1e-9:
            pub.publish(queue.popleft()[1])

    def camera_info_(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        info.header = Header(stamp, topics.CAMERA_OPTICAL_FRAME)
        pub.publish(info)

    def image(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        assert robot.camera is not None
        twist = robot.sim.twist
        pixels = robot.camera.render(
            robot.sim.pose, Motion(twist.linear_mps, twist.angular_radps), robot.sim.other_footprints()
        )
        robot.frames_rendered += 1
        height, width = pixels.shape
        pub.publish(
            Image(
                Header(stamp, topics.CAMERA_OPTICAL_FRAME),
                height,
                width,
                "mono8",
                0,
                width,
                pixels.reshape(-1),
            )
        )

    def contact(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        pub.publish(contact_message(robot, now))

    def ir(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        readings = robot.sim.dock_infrared()
        pub.publish(DockInfraRed(Header(stamp, topics.BASE_FRAME), np.array(readings, dtype=np.uint8)))

    def ground_truth(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        pub.publish(PoseStamped(Header(stamp, topics.MAP_FRAME), Pose.from_pose2d(robot.sim.pose)))

    def clock(robot: SimRobot, pub: Publisher[Any], now: float, stamp: Time) -> None:
        pub.publish(Clock(stamp))

    table = [
        Channel(topics.TF_STATIC, TFMessage, BLOCKING, params.tf.static_rate_hz, tf_static),
        Channel(topics.TF, TFMessage, RELIABLE, params.tf.rate_hz, tf),
        Channel(topics.ODOM, Odometry, RELIABLE, params.odom.rate_hz, odom),
        Channel(topics.SCAN, LaserScan, SENSOR_DATA, params.lidar.rate_hz, scan),
        Channel(topics.ULTRASONIC, Range, SENSOR_DATA, params.ultrasonic.rate_hz, ultrasonic),
    ]
    if not DETECTORS[params.detection.source].camera:
        # Captured only while someone listens, as the contract says: in a fleet most robots are not docking,
        # and detecting for them costs the simulator time for nobody (measurement 75).
        table.append(
            Channel(
                topics.DETECTED_DOCK_POSE,
                PoseStamped,
                SENSOR_DATA,
                params.detection.rate_hz,
                capture_detection,
                on_demand=True,
            )
        )
    table.append(Channel(topics.DETECTED_DOCK_POSE, PoseStamped, SENSOR_DATA, None, release_detections))
    if camera_params.enabled:
        table += [
            Channel(
                topics.CAMERA_INFO,
                CameraInfo,
                SENSOR_DATA,
                camera_params.rate_hz,
                camera_info_,
                on_demand=True,
            ),
            Channel(topics.CAMERA_IMAGE, Image, SENSOR_DATA, camera_params.rate_hz, image, on_demand=True),
        ]
    table += [
        Channel(topics.DOCK_CONTACT, DockContact, RELIABLE, params.contact.rate_hz, contact),
        Channel(topics.IR_DOCK, DockInfraRed, SENSOR_DATA, params.ir.rate_hz, ir, on_demand=True),
        Channel(topics.GROUND_TRUTH_POSE, PoseStamped, RELIABLE, params.ground_truth.rate_hz, ground_truth),
        Channel(topics.CLOCK, Clock, CLOCK_QOS, params.clock.rate_hz, clock),
    ]
    assert table[-1].topic == topics.CLOCK, "the clock goes out last in each step"
    return table


class Channels:
    """The table with its schedules: declares each robot's publishers and publishes what is due."""

    def __init__(self, table: Sequence[Channel]) -> None:
        self.table = tuple(table)
        self._schedules = [None if ch.rate_hz is None else Every(1.0 / ch.rate_hz) for ch in self.table]

    def declare(self, node: Any, robot: SimRobot) -> None:
        """One publisher per topic of the table, under the robot's prefix."""
        for ch in self.table:
            if ch.topic not in robot.pubs:
                robot.pubs[ch.topic] = node.create_publisher(ch.msg_type, robot.topic(ch.topic), ch.qos)

    def publish_due(self, robots: Sequence[SimRobot], now: float) -> None:
        due = [schedule is None or schedule.due(now) for schedule in self._schedules]
        stamp = Time.from_sec(now)
        for robot in robots:
            for ch, is_due in zip(self.table, due, strict=True):
                if not is_due:
                    continue
                pub = robot.pubs[ch.topic]
                if ch.on_demand and not pub.has_subscribers():
                    continue
                ch.publish(robot, pub, now, stamp)


__all__ = ["Channel", "Channels", "Every", "SimRobot", "channel_table", "contact_message", "tf_message"]
