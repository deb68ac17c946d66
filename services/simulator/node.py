"""The simulator service: steps the physics at a fixed 100 Hz and publishes clock, odometry, tf and sensors.

Time: sim time starts at 0 and advances ``dt`` per step; ``rtf`` paces it against the wall clock
(``max``: as fast as the machine allows). Every publication is stamped with sim time and ``clock`` is
published so the other services follow it.

One process can serve several robots (``robots: [r1, r2]``), each in its own copy of the room under its
own namespace, so trials can run robots side by side without a simulator each. With no ``robots`` the
one robot lives in the node's namespace. A world that lists its own ``robots`` (a fleet) puts them all
in one room instead: one physical space, robots colliding with and seeing each other, each under its
name as namespace (``robots`` then picks some of them; by default all).
"""

from __future__ import annotations

import dataclasses
import math
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from pydantic import Field, field_validator

from services.simulator.camera import CameraParams, CameraRenderer, Motion, build_scene
from services.simulator.camera_frames import camera_info, camera_mount_transforms
from services.simulator.dock_contact import DockContactParams
from services.simulator.pacing import Driver, DriverPacer, PacingParams
from services.simulator.physics import PoseInCollisionError, SimParams, SimWorld, step_together
from services.simulator.robot_model import DiffDriveParams
from services.simulator.sensors import FiducialCameraParams, LidarParams, UltrasonicParams
from shared import topics
from shared.config_errors import ConfigError
from shared.geometry import Pose2D
from shared.interfaces.simulator import (
    SET_LOCALISATION,
    SIM_STATE,
    TELEPORT,
    SetLocalisationRequest,
    SetLocalisationResponse,
    SimStateRequest,
    SimStateResponse,
    TeleportRequest,
    TeleportResponse,
)
from shared.memory import return_large_blocks
from shared.messages import (
    CameraInfo,
    Clock,
    CollisionEvent,
    DockContact,
    DockInfraRed,
    Float64MultiArray,
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
from shared.names import normalise_namespace
from shared.node import BLOCKING, RELIABLE, SENSOR_DATA, Node, Publisher, QoS, ServiceError
from shared.runtime import ServiceParams, ServiceSpec
from shared.world import load_world

#: How often the simulator logs the real-time factor it achieves (wall seconds).
RTF_REPORT_PERIOD_S = 30.0


class Params(ServiceParams):
    """Simulator parameters (``-p name=value``)."""

    world: str = Field(description="world file (deploy/worlds/*.yaml)")
    rtf: float | str = Field(1.0, description="real-time factor: a positive number, or 'max'")
    robots: list[str] = Field(default_factory=list, description="robot namespaces served (empty: the node's own)")
    seed: int = 0
    dt_s: float = Field(0.01, gt=0, le=0.05)
    clock_rate_hz: float = Field(20.0, gt=0, description="sim-time clock rate: the stack's fastest sim-time timer "
                                 "(planner and docking control, 20 Hz); every sim-time node receives every tick")
    odom_rate_hz: float = Field(20.0, gt=0, description="odometry rate: the control timers' 20 Hz (they read the latest)")
    tf_rate_hz: float = Field(20.0, gt=0, description="tf rate: twice the pose service's 10 Hz, on the clock's ticks")
    tf_static_rate_hz: float = Field(1.0, gt=0)
    scan_rate_hz: float = Field(10.0, gt=0)
    ultrasonic_rate_hz: float = Field(20.0, gt=0)
    detection_rate_hz: float = Field(15.0, gt=0)
    contact_rate_hz: float = Field(20.0, gt=0)
    ir_rate_hz: float = Field(20.0, gt=0, description="the infrared receivers' readings (ir_dock), while subscribed")
    ground_truth_rate_hz: float = Field(20.0, gt=0)
    cmd_vel_timeout_s: float = Field(
        0.3, gt=0, description="watchdog: brake when no command for this long (standing still 0.5 s after the last)")
    pace_to_drivers: bool = Field(
        True, description="wait (briefly) for a moving robot's late command instead of driving it blind")
    driver_gap_s: float = Field(0.15, gt=0, description="a moving robot's command older than this (sim) is late")
    driver_wait_max_s: float = Field(0.1, ge=0, description="wait at most this long (wall) for one late command")
    pace_to_pose: bool = Field(
        True, description="with pace_to_drivers: also wait (briefly) for a robot's late map_to_base_link_pose2d")
    pose_gap_s: float = Field(0.3, gt=0, description="a robot's pose older than this (sim) is late")
    # drive (Gazebo diff_drive / ros2_control names)
    wheel_separation_m: float = Field(0.26, gt=0)
    wheel_radius_m: float = Field(0.033, gt=0)
    max_linear_mps: float = Field(0.5, gt=0)
    max_angular_radps: float = Field(1.5, gt=0)
    max_linear_accel: float = Field(1.0, gt=0)
    max_angular_accel: float = Field(3.0, gt=0)
    max_linear_decel: float = Field(2.5, gt=0)
    max_angular_decel: float = Field(6.0, gt=0)
    # sensors
    lidar_noise_m: float = Field(0.01, ge=0)
    ultrasonic_noise_m: float = Field(0.005, ge=0)
    ultrasonic_fov_rad: float = Field(0.5, gt=0, lt=math.pi)
    ultrasonic_max_range_m: float = Field(3.0, gt=0)
    #: Who tells the docking service where the dock is: ``aruco`` leaves it to the perception service
    #: (which reads camera/image_raw); ``synthetic`` publishes detected_dock_pose from the true pose plus noise.
    dock_detector: Literal["aruco", "synthetic"] = "synthetic"
    detection_latency_s: float = Field(0.05, ge=0)
    detection_position_noise_m: float = Field(0.003, ge=0)
    detection_yaw_noise_rad: float = Field(0.01, ge=0)
    detection_fov_rad: float = Field(1.2, gt=0, lt=math.pi)
    detection_range_m: float = Field(2.5, gt=0)
    detection_min_range_m: float = Field(0.02, ge=0)
    # the rendered camera (camera/image_raw, camera/camera_info): frames are made only while someone subscribes
    camera_enabled: bool = True
    camera_width: int = Field(640, ge=16, le=4096)
    camera_height: int = Field(480, ge=16, le=4096)
    camera_hfov_rad: float = Field(math.radians(70.0), gt=0.1, lt=2.6)
    camera_rate_hz: float = Field(15.0, gt=0)
    camera_mount_z_m: float = Field(0.10, gt=0)
    camera_pitch_rad: float = Field(0.0, gt=-1.04, lt=1.04)
    camera_noise: float = Field(2.0, ge=0, description="read noise, grey levels (sigma)")
    camera_exposure_s: float = Field(0.008, ge=0, description="exposure time: sets motion blur")
    camera_gain: float = Field(1.0, gt=0)
    # localisation: map->odom is off by this much (in base_link at the start), like a drifting localiser
    localisation_error: tuple[float, float, float] = (0.0, 0.0, 0.0)
    odom_noise: float = Field(0.0, ge=0)

    @field_validator("rtf")
    @classmethod
    def _rtf(cls, value: float | str) -> float | str:
        if isinstance(value, str):
            if value.strip().lower() == "max":
                return "max"
            try:
                value = float(value)
            except ValueError:
                raise ValueError(f"rtf must be a positive number or 'max', got {value!r}") from None
        if not (value > 0 and math.isfinite(value)):
            raise ValueError(f"rtf must be a positive number or 'max', got {value}")
        return value

    @field_validator("world")
    @classmethod
    def _world_loads(cls, value: str) -> str:
        load_world(value)  # a ConfigError (a ValueError) names the file and the problem
        return value

    @field_validator("robots")
    @classmethod
    def _robots(cls, value: list[str]) -> list[str]:
        names = [normalise_namespace(v) for v in value]
        if any(not n for n in names) or len(set(names)) != len(names):
            raise ValueError("robots must be distinct, non-empty namespaces")
        return names

    def sim_params(self) -> SimParams:
        return SimParams(
            dt_s=self.dt_s,
            odom_noise=self.odom_noise,
            seed=self.seed,
            lidar=LidarParams(noise_sigma_m=self.lidar_noise_m),
            ultrasonic=UltrasonicParams(
                noise_sigma_m=self.ultrasonic_noise_m,
                field_of_view_rad=self.ultrasonic_fov_rad,
                range_max_m=self.ultrasonic_max_range_m,
            ),
            camera=FiducialCameraParams(
                horizontal_fov_rad=self.detection_fov_rad,
                range_max_m=self.detection_range_m,
                range_min_m=self.detection_min_range_m,
                position_sigma_m=self.detection_position_noise_m,
                yaw_sigma_rad=self.detection_yaw_noise_rad,
            ),
            contact=DockContactParams(),
            localisation_error=Pose2D(*self.localisation_error),
        )

    def camera_params(self) -> CameraParams:
        return CameraParams(
            width=self.camera_width, height=self.camera_height, horizontal_fov_rad=self.camera_hfov_rad,
            rate_hz=self.camera_rate_hz, mount_x_m=FiducialCameraParams().mount_x_m, mount_z_m=self.camera_mount_z_m,
            pitch_rad=self.camera_pitch_rad, noise_sigma=self.camera_noise, exposure_s=self.camera_exposure_s,
            gain=self.camera_gain,
        )

    def drive_params(self) -> DiffDriveParams:
        return DiffDriveParams(
            wheel_separation_m=self.wheel_separation_m,
            wheel_radius_m=self.wheel_radius_m,
            max_linear_mps=self.max_linear_mps,
            max_angular_radps=self.max_angular_radps,
            max_linear_accel=self.max_linear_accel,
            max_angular_accel=self.max_angular_accel,
            max_linear_decel=self.max_linear_decel,
            max_angular_decel=self.max_angular_decel,
        )


@dataclass
class _Every:
    """Fires every ``period_s`` of sim time."""

    period_s: float
    next_s: float = 0.0

    def due(self, now_s: float) -> bool:
        if now_s + 1e-9 < self.next_s:
            return False
        self.next_s = max(self.next_s + self.period_s, now_s + self.period_s * 0.5)
        return True


@dataclass
class _Robot:
    """One simulated robot and its endpoints on the bus."""

    namespace: str
    sim: SimWorld
    prefix: str
    pubs: dict[str, Publisher[Any]] = field(default_factory=dict)
    cmd_v: float = 0.0
    cmd_w: float = 0.0
    last_cmd_s: float = -math.inf
    #: Sim time of the last map_to_base_link_pose2d (the localisation the controllers steer on).
    last_pose_s: float = -math.inf
    watchdog_tripped: bool = True
    pending_detections: deque[tuple[float, PoseStamped]] = field(default_factory=deque)
    collisions_total: int = 0
    camera: CameraRenderer | None = None
    frames_rendered: int = 0

    def topic(self, name: str) -> str:
        return f"{self.prefix}{name}"


class SimulatorService:
    def __init__(self, node: Node, params: Params) -> None:
        self.node = node
        self.params = params
        self._log = node.log
        self.world = load_world(params.world)
        self.robots: dict[str, _Robot] = {}
        camera_params = params.camera_params()
        scene = build_scene(self.world) if params.camera_enabled else None
        starts = self._starts(params)
        #: Whether the robots share one room (a fleet world) and so step together.
        self.shared_room = bool(self.world.robots)
        room: SimWorld | None = None
        for i, (ns, start) in enumerate(starts.items()):
            sim_params = dataclasses.replace(params.sim_params(), seed=params.seed + i)
            try:
                if not self.shared_room:
                    sim = SimWorld(self.world, params.drive_params(), sim_params)
                elif room is None:
                    sim = room = SimWorld(self.world, params.drive_params(), sim_params, start=start, name=ns)
                else:
                    sim = room.join(ns, start, sim_params)
            except PoseInCollisionError as exc:
                raise ConfigError(f"{params.world}: {exc}") from None
            robot = _Robot(ns, sim, f"{ns}/" if ns else "")
            if scene is not None:
                robot.camera = CameraRenderer(scene, camera_params, np.random.default_rng([params.seed, i, 7]))
            self._declare(robot)
            self.robots[ns] = robot
        dt = params.dt_s
        self.dt_s = dt
        self.time_s = 0.0
        self._clock = _Every(1.0 / params.clock_rate_hz)
        self._odom = _Every(1.0 / params.odom_rate_hz)
        self._tf = _Every(1.0 / params.tf_rate_hz)
        self._tf_static = _Every(1.0 / params.tf_static_rate_hz)
        self._scan = _Every(1.0 / params.scan_rate_hz)
        self._sonar = _Every(1.0 / params.ultrasonic_rate_hz)
        self._detect = _Every(1.0 / params.detection_rate_hz)
        self._camera = _Every(1.0 / params.camera_rate_hz)
        self._camera_info = camera_info(camera_params)
        self._contact = _Every(1.0 / params.contact_rate_hz)
        self._ir = _Every(1.0 / params.ir_rate_hz)
        self._truth = _Every(1.0 / params.ground_truth_rate_hz)
        self._clock_pubs = [node.create_publisher(Clock, r.topic(topics.CLOCK), QoS(reliable=True, depth=1))
                            for r in self.robots.values()]
        node.create_service(TELEPORT, topics.SIM_TELEPORT, self._on_teleport)
        node.create_service(SET_LOCALISATION, topics.SIM_SET_LOCALISATION, self._on_set_localisation)
        node.create_service(SIM_STATE, topics.SIM_STATE, self._on_state)
        self.steps_run = 0
        self._pacer = (
            DriverPacer(PacingParams(params.driver_gap_s, params.driver_wait_max_s, params.pose_gap_s))
            if params.pace_to_drivers else None
        )
        self._running = True
        self._thread = threading.Thread(target=self._loop, name="sim-step", daemon=True)
        self._thread.start()
        rtf = params.rtf
        self._log.info("world %s, %d robot(s), rtf %s", self.world.name, len(self.robots), rtf)

    def _starts(self, params: Params) -> dict[str, Pose2D | None]:
        """Each robot's namespace and start: the world's fleet (those ``robots`` names, or all), else
        ``robots`` (or the node's own namespace) each at the world's ``robot.start`` in a room of its own."""
        fleet = {r.name: Pose2D.from_seq(r.start) for r in self.world.robots}
        if not fleet:
            return dict.fromkeys(params.robots or [""])
        unknown = [name for name in params.robots if name not in fleet]
        if unknown:
            raise ConfigError(f"robots {unknown} are not in {params.world}'s robots {sorted(fleet)}")
        return {name: fleet[name] for name in (params.robots or list(fleet))}

    # --- endpoints -----------------------------------------------------------------------------------

    def _declare(self, robot: _Robot) -> None:
        node = self.node
        t = robot.topic
        robot.pubs = {
            "odom": node.create_publisher(Odometry, t(topics.ODOM), RELIABLE),
            "tf": node.create_publisher(TFMessage, t(topics.TF), RELIABLE),
            "tf_static": node.create_publisher(TFMessage, t(topics.TF_STATIC), BLOCKING),
            "scan": node.create_publisher(LaserScan, t(topics.SCAN), SENSOR_DATA),
            "ultrasonic": node.create_publisher(Range, t(topics.ULTRASONIC), SENSOR_DATA),
            "detected_dock_pose": node.create_publisher(PoseStamped, t(topics.DETECTED_DOCK_POSE), SENSOR_DATA),
            "dock_contact": node.create_publisher(DockContact, t(topics.DOCK_CONTACT), RELIABLE),
            "ir_dock": node.create_publisher(DockInfraRed, t(topics.IR_DOCK), SENSOR_DATA),
            "collisions": node.create_publisher(CollisionEvent, t(topics.COLLISIONS), BLOCKING),
            "ground_truth_pose": node.create_publisher(PoseStamped, t(topics.GROUND_TRUTH_POSE), RELIABLE),
        }
        if self.params.camera_enabled:
            robot.pubs["image"] = node.create_publisher(Image, t(topics.CAMERA_IMAGE), SENSOR_DATA)
            robot.pubs["camera_info"] = node.create_publisher(CameraInfo, t(topics.CAMERA_INFO), SENSOR_DATA)
        node.create_subscription(Twist, t(topics.CMD_VEL), lambda msg, r=robot: self._on_cmd_vel(r, msg), QoS(depth=1))
        if self.params.pace_to_drivers and self.params.pace_to_pose:
            # Only the arrival time is kept: one float store, safe on Zenoh's thread (no executor hand-off).
            node.create_subscription(Float64MultiArray, t(topics.POSE2D), lambda _msg, r=robot: self._on_pose(r),
                                     QoS(depth=1), inline=True)

    def _on_cmd_vel(self, robot: _Robot, msg: Twist) -> None:
        robot.cmd_v = msg.linear.x
        robot.cmd_w = msg.angular.z
        robot.last_cmd_s = self.time_s
        robot.watchdog_tripped = False

    def _on_pose(self, robot: _Robot) -> None:
        robot.last_pose_s = self.time_s

    def _robot_for(self, name: str) -> _Robot:
        ns = normalise_namespace(name)
        if ns not in self.robots:
            raise ServiceError(f"no robot {name!r} in this simulator (robots: {sorted(self.robots) or ['']})")
        return self.robots[ns]

    def _on_teleport(self, request: TeleportRequest) -> TeleportResponse:
        robot = self._robot_for(request.robot)
        try:
            robot.sim.teleport(Pose2D.from_seq((request.x, request.y, request.yaw)))
        except PoseInCollisionError as exc:
            return TeleportResponse(success=False, message=str(exc))
        robot.cmd_v = robot.cmd_w = 0.0
        robot.pending_detections.clear()
        self._publish_tf(robot, self.time_s)
        return TeleportResponse(success=True, message="")

    def _on_set_localisation(self, request: SetLocalisationRequest) -> SetLocalisationResponse:
        robot = self._robot_for(request.robot)
        belief = Pose2D.from_seq((request.x, request.y, request.yaw))
        robot.sim.believe(belief)
        self._publish_tf(robot, self.time_s)
        error = robot.sim.params.localisation_error
        self.node.log.info("localiser set to believe (%.3f, %.3f, %.3f): error now (%.3f m, %.3f m, %.3f rad)",
                           belief.x, belief.y, belief.yaw, error.x, error.y, error.yaw)
        return SetLocalisationResponse(success=True, message="")

    def _on_state(self, request: SimStateRequest) -> SimStateResponse:
        robot = self._robot_for(request.robot)
        return SimStateResponse(
            stamp=Time.from_sec(self.time_s),
            world=self.world.name,
            pose=Pose.from_pose2d(robot.sim.pose),
            collisions=robot.collisions_total,
            contact=self._contact_msg(robot, self.time_s),
        )

    # --- stepping ------------------------------------------------------------------------------------

    def _loop(self) -> None:
        """Step in real time times ``rtf`` (or flat out), publishing what is due after each step.

        With ``pace_to_drivers`` the world also waits for late drivers (:mod:`services.simulator.pacing`)
        and does not rush to catch up afterwards: the clock resumes at the target rate from there.
        """
        rtf = self.params.rtf
        wall_per_step = 0.0 if rtf == "max" else self.dt_s / float(rtf)
        next_wall = time.monotonic()
        held_since: float | None = None
        reported_at = (time.monotonic(), self.time_s)
        while self._running:
            now = time.monotonic()
            if self._pacer is not None and self._pacer.hold(self.time_s, now, self._drivers()):
                held_since = now if held_since is None else held_since
                time.sleep(0.0005)
                continue
            if held_since is not None:
                assert self._pacer is not None
                self._pacer.note_held(now - held_since)
                self._publish_pacing_stats()
                held_since = None
                next_wall = now
            if wall_per_step > 0.0:
                if now < next_wall:
                    time.sleep(min(next_wall - now, 0.05))
                    continue
                if now - next_wall > 0.25:  # fell far behind (machine busy): do not try to catch up
                    next_wall = now
                next_wall += wall_per_step
            with self.node.exclusive():
                self._step_once()
            if now - reported_at[0] >= RTF_REPORT_PERIOD_S:
                reported_at = self._report_rate(now, reported_at)

    def _publish_pacing_stats(self) -> None:
        """The waits for late drivers in the node's counters (``@zendock/stats``: ``zendock bench messages``)."""
        pacer = self._pacer
        assert pacer is not None
        extra = {"pacing_holds": float(pacer.holds), "pacing_held_s": pacer.held_s, "sim_s": self.time_s}
        extra.update({f"pacing_held_s_{kind}": s for kind, s in pacer.held_by_kind.items()})
        self.node.stats.extra = extra  # one assignment: the stats query reads a whole dict

    def _drivers(self) -> list[Driver]:
        drivers = []
        for ns, robot in self.robots.items():
            moving = not robot.watchdog_tripped and (robot.cmd_v != 0.0 or robot.cmd_w != 0.0)
            drivers.append(Driver(ns, robot.last_cmd_s, moving))
            if robot.last_pose_s > -math.inf:
                drivers.append(Driver(f"{ns}:pose", robot.last_pose_s, True, self.params.pose_gap_s))
        return drivers

    def _report_rate(self, wall_now: float, since: tuple[float, float]) -> tuple[float, float]:
        """Log the real-time factor achieved since the last report, and the waits for late drivers."""
        wall_then, sim_then = since
        achieved = (self.time_s - sim_then) / max(wall_now - wall_then, 1e-9)
        pacer = self._pacer
        waits = f"; waited for late drivers {pacer.holds} times, {pacer.held_s:.1f} s in all" if pacer else ""
        self._log.info("real-time factor %.1f over the last %.0f s (target %s)%s",
                      achieved, wall_now - wall_then, self.params.rtf, waits)
        return wall_now, self.time_s

    def _step_once(self) -> None:
        self.steps_run += 1
        self.time_s = self.steps_run * self.dt_s
        now = self.time_s
        robots = list(self.robots.values())
        for robot in robots:
            if not robot.watchdog_tripped and now - robot.last_cmd_s > self.params.cmd_vel_timeout_s:
                robot.watchdog_tripped = True
                robot.cmd_v = robot.cmd_w = 0.0
        if self.shared_room:
            step_together([r.sim for r in robots], [(r.cmd_v, r.cmd_w) for r in robots])
        else:
            for robot in robots:
                robot.sim.step(robot.cmd_v, robot.cmd_w)
        for robot in robots:
            for event in robot.sim.drain_collisions():
                robot.collisions_total += 1
                robot.pubs["collisions"].publish(CollisionEvent(
                    Header.at(event.time_s, topics.MAP_FRAME), event.kind, robot.collisions_total, event.x_m, event.y_m,
                    other_robot=event.other_robot or ""))
                what = f"robot {event.other_robot}" if event.other_robot else event.kind
                self._log.warning("%scollision with %s at (%.2f, %.2f), %.2f m/s", robot.prefix, what, event.x_m,
                                  event.y_m, event.speed_mps)
        self._publish_due(now)

    def _publish_due(self, now: float) -> None:
        clock = self._clock.due(now)
        odom, tf, tf_static = self._odom.due(now), self._tf.due(now), self._tf_static.due(now)
        scan, sonar, detect = self._scan.due(now), self._sonar.due(now), self._detect.due(now)
        contact, truth = self._contact.due(now), self._truth.due(now)
        camera = self._camera.due(now)
        ir = self._ir.due(now)
        stamp = Time.from_sec(now)
        for i, robot in enumerate(self.robots.values()):
            if tf_static:
                self._publish_tf_static(robot, stamp)
            if tf:
                self._publish_tf(robot, now)
            if odom:
                self._publish_odom(robot, stamp)
            if scan:
                self._publish_scan(robot, stamp)
            if sonar:
                self._publish_sonar(robot, stamp)
            if detect and self.params.dock_detector == "synthetic":
                self._capture_detection(robot, now)
            self._release_detections(robot, now)
            if camera and robot.camera is not None:
                self._publish_camera(robot, stamp)
            if contact:
                robot.pubs["dock_contact"].publish(self._contact_msg(robot, now))
            if ir and robot.pubs["ir_dock"].has_subscribers():
                readings = robot.sim.dock_infrared()
                robot.pubs["ir_dock"].publish(DockInfraRed(Header(stamp, topics.BASE_FRAME),
                                                           np.array(readings, dtype=np.uint8)))
            if truth:
                robot.pubs["ground_truth_pose"].publish(
                    PoseStamped(Header(stamp, topics.MAP_FRAME), Pose.from_pose2d(robot.sim.pose)))
            # The clock last: a sim-time timer it wakes then acts on this step's odometry, tf and sensors,
            # which went out before it on the same link, not on the step before.
            if clock:
                self._clock_pubs[i].publish(Clock(stamp))

    def _publish_tf(self, robot: _Robot, now: float) -> None:
        stamp = Time.from_sec(now)
        map_to_odom = robot.sim.map_to_odom()
        odom_to_base = robot.sim.odom_pose
        robot.pubs["tf"].publish(TFMessage([
            TransformStamped(Header(stamp, topics.MAP_FRAME), topics.ODOM_FRAME, Transform.from_pose2d(map_to_odom)),
            TransformStamped(Header(stamp, topics.ODOM_FRAME), topics.BASE_FRAME, Transform.from_pose2d(odom_to_base)),
        ]))

    def _publish_tf_static(self, robot: _Robot, stamp: Time) -> None:
        p = robot.sim.params
        mounts = [
            (topics.LIDAR_FRAME, Pose2D(p.lidar.mount_x_m, p.lidar.mount_y_m, 0.0)),
            (topics.ULTRASONIC_FRAME, Pose2D(p.ultrasonic.mount_x_m, 0.0, 0.0)),
        ]
        transforms = [TransformStamped(Header(stamp, topics.BASE_FRAME), child, Transform.from_pose2d(mount))
                      for child, mount in mounts]
        transforms += camera_mount_transforms(self.params.camera_params(), stamp)
        robot.pubs["tf_static"].publish(TFMessage(transforms))

    def _publish_camera(self, robot: _Robot, stamp: Time) -> None:
        """A rendered frame and its calibration, each only while someone subscribes to it."""
        assert robot.camera is not None
        info_pub, image_pub = robot.pubs["camera_info"], robot.pubs["image"]
        if info_pub.has_subscribers():
            info = self._camera_info
            info.header = Header(stamp, topics.CAMERA_OPTICAL_FRAME)
            info_pub.publish(info)
        if not image_pub.has_subscribers():
            return
        twist = robot.sim.twist
        pixels = robot.camera.render(robot.sim.pose, Motion(twist.linear_mps, twist.angular_radps),
                                     robot.sim.other_footprints())
        robot.frames_rendered += 1
        height, width = pixels.shape
        image_pub.publish(Image(Header(stamp, topics.CAMERA_OPTICAL_FRAME), height, width, "mono8", 0, width,
                                pixels.reshape(-1)))

    def _publish_odom(self, robot: _Robot, stamp: Time) -> None:
        twist = robot.sim.twist
        robot.pubs["odom"].publish(Odometry(
            Header(stamp, topics.ODOM_FRAME),
            topics.BASE_FRAME,
            PoseWithCovariance(Pose.from_pose2d(robot.sim.odom_pose)),
            TwistWithCovariance(Twist.planar(twist.linear_mps, twist.angular_radps)),
        ))

    def _publish_scan(self, robot: _Robot, stamp: Time) -> None:
        scan = robot.sim.lidar_scan()
        n = len(scan.ranges_m)
        robot.pubs["scan"].publish(LaserScan(
            header=Header(stamp, topics.LIDAR_FRAME),
            angle_min=scan.angle_min_rad,
            angle_max=scan.angle_min_rad + scan.angle_increment_rad * (n - 1),
            angle_increment=scan.angle_increment_rad,
            time_increment=0.0,
            scan_time=self._scan.period_s,
            range_min=scan.range_min_m,
            range_max=scan.range_max_m,
            ranges=np.asarray(scan.ranges_m, dtype=np.float32),
            intensities=np.zeros(0, dtype=np.float32),
        ))

    def _publish_sonar(self, robot: _Robot, stamp: Time) -> None:
        p = robot.sim.params.ultrasonic
        robot.pubs["ultrasonic"].publish(Range(
            header=Header(stamp, topics.ULTRASONIC_FRAME),
            radiation_type=Range.ULTRASOUND,
            field_of_view=p.field_of_view_rad,
            min_range=p.range_min_m,
            max_range=p.range_max_m,
            range=float(robot.sim.ultrasonic_range()),
        ))

    def _capture_detection(self, robot: _Robot, now: float) -> None:
        detection = robot.sim.detect_dock()
        if detection is None:
            return
        msg = PoseStamped(Header.at(now, topics.BASE_FRAME), Pose.from_pose2d(detection.dock_pose_in_base))
        robot.pending_detections.append((now + self.params.detection_latency_s, msg))

    def _release_detections(self, robot: _Robot, now: float) -> None:
        queue = robot.pending_detections
        while queue and queue[0][0] <= now + 1e-9:
            robot.pubs["detected_dock_pose"].publish(queue.popleft()[1])

    def _contact_msg(self, robot: _Robot, now: float) -> DockContact:
        c = robot.sim.dock_contact()
        finite = [v if v is not None and math.isfinite(v) else 0.0 for v in (c.lateral_error_m, c.yaw_error_rad, c.along_error_m)]
        return DockContact(Header.at(now, topics.MAP_FRAME), c.dock_id or "", bool(c.mated), bool(c.touching), *finite)

    def close(self) -> None:
        self._running = False
        self._thread.join(timeout=2.0)


def _add_flags(parser: Any) -> dict[str, str]:
    parser.add_argument("--world", default=None, help="world file (same as -p world=FILE)")
    parser.add_argument("--rtf", default=None, help="real-time factor or 'max' (same as -p rtf=...)")
    return {"world": "world", "rtf": "rtf"}


SERVICE = ServiceSpec("simulator", Params, SimulatorService,
                      description="zendock simulator: physics, clock, odometry, tf and sensors",
                      add_flags=_add_flags,
                      prepare=return_large_blocks)  # camera frames: image-sized temporaries at 15 Hz


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
