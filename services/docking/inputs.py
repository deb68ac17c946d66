"""What the docking service hears, kept with its freshness, and handed to the executive as one snapshot.

:class:`InputCache` stores the latest of each input as it arrives (callbacks only store) and
:meth:`InputCache.heard` returns a :class:`~services.docking.heard.Heard` snapshot at the node's clock:
stale readings are left out there, so the executive never compares ages. No clock of its own (times are
passed in); the snapshot's types live in :mod:`services.docking.heard`, which the executive imports
without the bus.

:class:`DockSightings` is the one input with a life of its own, as Nav2 keeps it in the dock plugin: the
detection subscription is declared only while a docking run wants detections (the perception service
sees no subscriber otherwise, stops reading images, and the simulator stops rendering them), and each
detection is handed on with the robot's map pose at its stamp.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from services.docking.heard import CHARGING_STATUSES, SENSOR_MAX_AGE_S, DockSighting, Heard, NavHeard
from services.docking.ir_run import IR_MAX_AGE_S
from services.docking.params import Params
from services.docking.safety import LidarReturns
from services.docking.traffic import Peer, PlanPoints
from shared import topics
from shared.frames import SensorMounts
from shared.geometry import Pose2D
from shared.messages import BatteryState, DockInfraRed, Odometry, PoseStamped, TFMessage
from shared.node import SENSOR_DATA, Node, Subscription
from shared.pose_tracking import OdometrySample, PoseTrack
from shared.ratelimit import RateLimitedLogger


class InputCache:
    """The latest of each input with the node-clock time it arrived; see the module docstring."""

    def __init__(self, params: Params, warn: RateLimitedLogger) -> None:
        self.params = params
        self._warn = warn
        self.track = PoseTrack()
        self.mounts = SensorMounts()
        self._battery: BatteryState | None = None
        self._battery_received_s = -math.inf
        self._scan: LidarReturns | None = None
        self._scan_received_s = -math.inf
        self._sonar_range_m = math.inf
        self._sonar_received_s = -math.inf
        self._ir_dock: tuple[int, int, int] | None = None
        self._ir_received_s = -math.inf

    # --- what arrives --------------------------------------------------------------------------------

    def battery(self, msg: BatteryState, now_s: float) -> None:
        self._battery, self._battery_received_s = msg, now_s

    def pose(self, data: np.ndarray, now_s: float) -> None:
        if len(data) < 3 or not np.all(np.isfinite(data[:3])):
            self._warn.warning("pose", "ignored a %s message without a finite [x, y, yaw]", topics.POSE2D)
            return
        self.track.add_pose(now_s, Pose2D.from_seq(data[:3]), self.params.pose_latency_s)

    def odometry(self, msg: Odometry, now_s: float) -> None:
        twist = msg.twist.twist
        # An odometry jump (the robot was moved) makes the track ignore localisation for a while: the
        # localiser may still report where the robot was.
        self.track.add_odom(
            OdometrySample(
                msg.header.stamp.to_sec(), msg.pose.pose.to_pose2d(), twist.linear.x, twist.angular.z
            ),
            now_s,
        )

    def scan(self, ranges: np.ndarray, angle_min: float, angle_increment: float, now_s: float) -> None:
        lidar_mount = self.mounts.get(topics.LIDAR_FRAME)
        if lidar_mount is None:
            return
        self._scan = LidarReturns(ranges, angle_min, angle_increment, lidar_mount)
        self._scan_received_s = now_s

    def sonar(self, range_m: float, now_s: float) -> None:
        self._sonar_range_m, self._sonar_received_s = float(range_m), now_s

    def infrared(self, msg: DockInfraRed, now_s: float) -> None:
        if msg.data.size != 3:
            self._warn.warning(
                "ir-dock",
                "ignored an ir_dock message with %d readings (expected right, central, left)",
                msg.data.size,
            )
            return
        self._ir_dock = (int(msg.data[0]), int(msg.data[1]), int(msg.data[2]))
        self._ir_received_s = now_s

    def tf_static(self, msg: TFMessage) -> None:
        self.mounts.update(msg)

    def forget_poses(self) -> None:
        """The clock went back (a reset): the pose history belongs to another time."""
        self.track.clear()

    # --- what the executive sees ---------------------------------------------------------------------

    def heard(
        self,
        now_s: float,
        nav: NavHeard | None = None,
        peers: tuple[Peer, ...] = (),
        own_plan: PlanPoints = None,
        clock_reset: bool = False,
    ) -> Heard:
        p = self.params
        track = self.track
        latest = track.latest()
        robot_pose: Pose2D | None = None
        pose_age_s = 0.0
        if latest is not None and track.pose_fresh(now_s, p.max_pose_age_s, p.max_localisation_age_s):
            robot_pose, pose_age_s = latest[1], max(0.0, now_s - latest[0])
        battery = self._battery
        odom = track.latest_odom
        return Heard(
            now_s=now_s,
            clock_reset=clock_reset,
            latest_pose=latest[1] if latest is not None else None,
            robot_pose=robot_pose,
            pose_age_s=pose_age_s,
            base_twist=track.twist(now_s, SENSOR_MAX_AGE_S),
            battery=float(battery.percentage) if battery is not None else None,
            charging=(
                battery is not None
                and now_s - self._battery_received_s <= p.battery_timeout_s
                and battery.power_supply_status in CHARGING_STATUSES
            ),
            scan=self._scan if now_s - self._scan_received_s <= SENSOR_MAX_AGE_S else None,
            sonar_range_m=self._sonar_range_m if now_s - self._sonar_received_s <= SENSOR_MAX_AGE_S else None,
            ir_dock=self._ir_dock if now_s - self._ir_received_s <= IR_MAX_AGE_S else None,
            map_to_odom=track.map_to_odom,
            nav=nav if nav is not None else NavHeard(),
            peers=peers,
            own_plan=own_plan,
            localisation_age_s=now_s - track.last_pose_received_s,
            odometry_age_s=now_s - odom.stamp_s if odom is not None else math.inf,
        )


class DockSightings:
    """The detection subscription, declared only while wanted; see the module docstring."""

    def __init__(
        self,
        node: Node,
        track: PoseTrack,
        warn: RateLimitedLogger,
        on_sighting: Callable[[DockSighting], None],
    ) -> None:
        self._node = node
        self._track = track
        self._warn = warn
        self._on_sighting = on_sighting
        self._subscription: Subscription[PoseStamped] | None = None

    @property
    def subscribed(self) -> bool:
        return self._subscription is not None

    def want(self, wanted: bool) -> None:
        """Subscribed exactly while the run wants detections: each frame wanted is one rendered and searched,
        and the run's wish starts and ends once per approach (a lingering subscription costs frames with no
        marker in them: measurement 66)."""
        if wanted and self._subscription is None:
            self._subscription = self._node.create_subscription(
                PoseStamped, topics.DETECTED_DOCK_POSE, self._on_detection, SENSOR_DATA
            )
        elif not wanted and self._subscription is not None:
            self._subscription.undeclare()
            self._subscription = None

    def _on_detection(self, msg: PoseStamped) -> None:
        if msg.header.frame_id not in ("", topics.BASE_FRAME):
            self._warn.warning(
                "detection-frame",
                "ignored a dock detection in frame %r (expected %s)",
                msg.header.frame_id,
                topics.BASE_FRAME,
            )
            return
        stamp_s = msg.header.stamp.to_sec()
        robot_at_stamp = self._track.pose_now_at(stamp_s)
        if robot_at_stamp is None:
            self._warn.info("detection-pose", "no robot pose at a detection's stamp %.3f s: ignored", stamp_s)
            return
        self._on_sighting(DockSighting(msg.pose.to_pose2d(), robot_at_stamp, stamp_s))
