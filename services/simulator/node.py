"""The simulator service: steps the physics at a fixed 100 Hz and publishes clock, odometry, tf and sensors.

Time: sim time starts at 0 and advances ``dt`` per step; ``rtf`` paces it against the wall clock
(``max``: as fast as the machine allows). Every publication is stamped with sim time and ``clock`` is
published so the other services follow it.

One process can serve several robots (``robots: [r1, r2]``), each in its own copy of the room under its
own namespace, so trials can run robots side by side without a simulator each. With no ``robots`` the
one robot lives in the node's namespace. A world that lists its own ``robots`` (a fleet) puts them all
in one room instead: one physical space, robots colliding with and seeing each other, each under its
name as namespace (``robots`` then picks some of them; by default all).

This module is wiring only: parameters in :mod:`~services.simulator.params`, what is published and when
in :mod:`~services.simulator.channels`, pacing against the wall clock in :mod:`~services.simulator.pacing`.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import numpy as np

from services.simulator.camera import CameraRenderer, ReadNoise, build_scene
from services.simulator.channels import Channels, SimRobot, channel_table, contact_message, tf_message
from services.simulator.pacing import Driver, DriverPacer, StepPacer, pacing_stats, rate_report
from services.simulator.params import Params
from services.simulator.physics import PoseInCollisionError, Robot, step_together
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
from shared.messages import CollisionEvent, Float64MultiArray, Header, PacingHold, Pose, Time, Twist
from shared.names import normalise_namespace
from shared.node import BLOCKING, Node, QoS, ServiceError
from shared.ratelimit import RateLimitedLogger
from shared.runtime import ServiceSpec
from shared.world import load_world

#: How often the simulator logs the real-time factor it achieves (wall seconds).
RTF_REPORT_PERIOD_S = 30.0


class SimulatorService:
    def __init__(self, node: Node, params: Params) -> None:
        self.node = node
        self.params = params
        self._log = node.log
        self._say = RateLimitedLogger(node.log, interval_s=5.0)
        self.world = load_world(params.world)
        self.robots: dict[str, SimRobot] = {}
        self.channels = Channels(channel_table(params))
        scene = build_scene(self.world) if params.camera.enabled else None
        noise = ReadNoise(np.random.default_rng([params.seed, 7])) if scene is not None else None
        #: Whether the robots share one room (a fleet world) and so step together.
        self.shared_room = bool(self.world.robots)
        room: Robot | None = None
        for i, (ns, start) in enumerate(self._starts(params).items()):
            sim_params = params.sim_params(robot_index=i)
            try:
                if not self.shared_room:
                    sim = Robot(self.world, params.drive, sim_params)
                elif room is None:
                    sim = room = Robot(self.world, params.drive, sim_params, start=start, name=ns)
                else:
                    assert start is not None, (
                        "a shared room's robots are the world's fleet, each with its start"
                    )
                    sim = room.join(ns, start, sim_params)
            except PoseInCollisionError as exc:
                raise ConfigError(f"{params.world}: {exc}") from None
            robot = SimRobot(ns, sim, f"{ns}/" if ns else "")
            if scene is not None:
                robot.camera = CameraRenderer(
                    scene, params.camera, np.random.default_rng([params.seed, i, 7]), noise
                )
            self._declare(robot)
            self.robots[ns] = robot
        self.dt_s = params.dt_s
        self.time_s = 0.0
        node.create_service(TELEPORT, topics.SIM_TELEPORT, self._on_teleport)
        node.create_service(SET_LOCALISATION, topics.SIM_SET_LOCALISATION, self._on_set_localisation)
        node.create_service(SIM_STATE, topics.SIM_STATE, self._on_state)
        self.steps_run = 0
        self._pacer = DriverPacer(params.pacing) if params.pacing.to_drivers else None
        self._running = True
        self._thread = threading.Thread(target=self._loop, name="sim-step", daemon=True)
        self._thread.start()
        self._log.info("world %s, %d robot(s), rtf %s", self.world.name, len(self.robots), params.rtf)

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

    def _declare(self, robot: SimRobot) -> None:
        node = self.node
        t = robot.topic
        self.channels.declare(node, robot)
        robot.pubs[topics.COLLISIONS] = node.create_publisher(CollisionEvent, t(topics.COLLISIONS), BLOCKING)
        node.create_subscription(
            Twist,
            t(topics.CMD_VEL),
            lambda msg, answered, r=robot: self._on_cmd_vel(r, msg, answered),
            QoS(depth=1),
            with_answered=True,
        )
        if self.params.pacing.to_drivers:
            node.create_subscription(
                PacingHold,
                t(topics.PACING_HOLD),
                lambda msg, r=robot: self._on_hold(r, msg),
                QoS(depth=4),
            )
        if self.params.pacing.to_drivers and self.params.pacing.to_pose:
            # Only the arrival time is kept: one float store, safe on Zenoh's thread (no executor hand-off).
            node.create_subscription(
                Float64MultiArray,
                t(topics.POSE2D),
                lambda _msg, r=robot: self._on_pose(r),
                QoS(depth=1),
                inline=True,
            )

    def _on_cmd_vel(self, robot: SimRobot, msg: Twist, answered_s: float | None) -> None:
        """A command; ``answered_s`` is the control tick it was computed on, when its publisher says (never
        later than now: a stamp from the future, say a controller still on a restarted simulator's clock,
        counts as arriving now)."""
        now = self.time_s
        robot.cmd_v = msg.linear.x
        robot.cmd_w = msg.angular.z
        robot.last_cmd_s = now
        robot.answered_s = now if answered_s is None else min(now, answered_s)
        robot.cadence.heard(robot.answered_s, self.dt_s)
        robot.handoff.driven(robot.answered_s, moving=robot.cmd_v != 0.0 or robot.cmd_w != 0.0)
        robot.watchdog_tripped = False

    def _on_hold(self, robot: SimRobot, msg: PacingHold) -> None:
        robot.handoff.heard(msg.header.stamp.to_sec(), msg.holder, msg.hold, self.time_s, msg.until_driven)

    def _on_pose(self, robot: SimRobot) -> None:
        robot.last_pose_s = self.time_s

    def _robot_for(self, name: str) -> SimRobot:
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
        robot.pubs[topics.TF].publish(tf_message(robot, self.time_s))
        return TeleportResponse(success=True, message="")

    def _on_set_localisation(self, request: SetLocalisationRequest) -> SetLocalisationResponse:
        robot = self._robot_for(request.robot)
        belief = Pose2D.from_seq((request.x, request.y, request.yaw))
        if not all(math.isfinite(v) for v in belief.as_tuple()):
            return SetLocalisationResponse(
                success=False, message=f"the pose {belief.as_tuple()} is not finite"
            )
        agreement = robot.sim.lidar_agreement(belief)
        needed = self.params.localisation.initial_pose_min_agreement
        if agreement < needed:
            believed = robot.sim.believed_pose()
            message = (
                f"initial pose ({belief.x:.2f}, {belief.y:.2f}, {belief.yaw:.2f}) refused: {100 * agreement:.0f}% "
                f"of the lidar's beams agree with the map seen from there (at least {100 * needed:.0f}% needed); "
                f"the localiser keeps ({believed.x:.2f}, {believed.y:.2f}, {believed.yaw:.2f})"
            )
            self.node.log.warning("%s", message)
            return SetLocalisationResponse(success=False, message=message)
        robot.sim.believe(belief)
        robot.pubs[topics.TF].publish(tf_message(robot, self.time_s))
        error = robot.sim.params.localisation_error
        self.node.log.info(
            "localiser set to believe (%.3f, %.3f, %.3f): error now (%.3f m, %.3f m, %.3f rad)",
            belief.x,
            belief.y,
            belief.yaw,
            error.x,
            error.y,
            error.yaw,
        )
        return SetLocalisationResponse(success=True, message="")

    def _on_state(self, request: SimStateRequest) -> SimStateResponse:
        robot = self._robot_for(request.robot)
        return SimStateResponse(
            stamp=Time.from_sec(self.time_s),
            world=self.world.name,
            pose=Pose.from_pose2d(robot.sim.pose),
            collisions=robot.collisions_total,
            contact=contact_message(robot, self.time_s),
        )

    # --- stepping ------------------------------------------------------------------------------------

    def _loop(self) -> None:
        """Step in real time times ``rtf`` (or flat out), publishing what is due after each step; the
        :class:`~services.simulator.pacing.StepPacer` says when (and holds for late drivers)."""
        pacer = StepPacer(self.dt_s, self.params.rtf, self._pacer, time.monotonic())
        reported_at = (time.monotonic(), self.time_s)
        gave_up = 0
        while self._running:
            now = time.monotonic()
            tick = pacer.tick(now, self.time_s, self._drivers)
            if self._pacer is not None and self._pacer.gave_up != gave_up:
                gave_up = self._pacer.gave_up
                self._log_gave_up(self._pacer)
            if tick.hold_ended:
                assert self._pacer is not None
                self.node.stats.extra = pacing_stats(self._pacer, self.time_s)  # one assignment: read whole
            if not tick.step:
                time.sleep(tick.sleep_s)
                continue
            with self.node.exclusive():
                self._step_once()
            if now - reported_at[0] >= RTF_REPORT_PERIOD_S:
                self._log.info(
                    "%s",
                    rate_report(
                        self.time_s - reported_at[1], now - reported_at[0], self.params.rtf, self._pacer
                    ),
                )
                reported_at = (now, self.time_s)

    def _log_gave_up(self, pacer: DriverPacer) -> None:
        late = ", ".join(f"{name} ({late_s:.2f} s late)" for name, late_s in pacer.gave_up_on)
        # Not a fault: a controller slower than the world's pace (a long first plan, a busy machine).
        self._say.info(
            "gave up",
            "stepping on at %.2f s without %s: waited %g s (wall) for it (%d times so far)",
            self.time_s,
            late,
            pacer.gave_up_after_s,
            pacer.gave_up,
        )

    def _drivers(self) -> list[Driver]:
        drivers = []
        pacing = self.params.pacing
        for ns, robot in self.robots.items():
            gap = robot.cadence.gap_s(pacing, self.dt_s)
            moving = robot.cmd_v != 0.0 or robot.cmd_w != 0.0
            # A command that arrived already answering an old tick says its controller is still at work on
            # that tick (a planner making its first plan holds its robot still with such stops): its robot
            # is awaited though it stands.
            thinking = robot.last_cmd_s - robot.answered_s > (pacing.driver_gap_s if gap is None else gap)
            awaited = not robot.watchdog_tripped and (moving or thinking)
            drivers.append(Driver(ns, robot.answered_s, awaited, gap))
            handoff_s = robot.handoff.current(self.time_s)
            if handoff_s is not None:
                # Between two drivers: wait as for a late command until the next one drives.
                drivers.append(Driver(f"{ns}:hold", handoff_s, True, gap))
            if robot.last_pose_s > -math.inf:
                drivers.append(Driver(f"{ns}:pose", robot.last_pose_s, True, pacing.pose_gap_s))
        return drivers

    def _step_once(self) -> None:
        self.steps_run += 1
        self.time_s = self.steps_run * self.dt_s
        now = self.time_s
        robots = list(self.robots.values())
        for robot in robots:
            if not robot.watchdog_tripped and now - robot.last_cmd_s > self.params.drive.cmd_vel_timeout_s:
                robot.watchdog_tripped = True
                robot.cmd_v = robot.cmd_w = 0.0
        if self.shared_room:
            step_together([r.sim for r in robots], [(r.cmd_v, r.cmd_w) for r in robots])
        else:
            for robot in robots:
                robot.sim.step(robot.cmd_v, robot.cmd_w)
        for robot in robots:
            self._publish_collisions(robot)
        self.channels.publish_due(robots, now)

    def _publish_collisions(self, robot: SimRobot) -> None:
        for event in robot.sim.drain_collisions():
            robot.collisions_total += 1
            robot.pubs[topics.COLLISIONS].publish(
                CollisionEvent(
                    Header.at(event.time_s, topics.MAP_FRAME),
                    event.kind,
                    robot.collisions_total,
                    event.x_m,
                    event.y_m,
                    other_robot=event.other_robot or "",
                )
            )
            what = f"robot {event.other_robot}" if event.other_robot else event.kind
            self._log.warning(
                "%scollision with %s at (%.2f, %.2f), %.2f m/s",
                robot.prefix,
                what,
                event.x_m,
                event.y_m,
                event.speed_mps,
            )

    def close(self) -> None:
        self._running = False
        self._thread.join(timeout=2.0)


def _add_flags(parser: Any) -> dict[str, str]:
    parser.add_argument("--world", default=None, help="world file (same as -p world=FILE)")
    parser.add_argument("--rtf", default=None, help="real-time factor or 'max' (same as -p rtf=...)")
    return {"world": "world", "rtf": "rtf"}


SERVICE = ServiceSpec(
    "simulator",
    Params,
    SimulatorService,
    description="zendock simulator: physics, clock, odometry, tf and sensors",
    add_flags=_add_flags,
)


def main(argv: list[str] | None = None) -> int:
    return SERVICE.run(argv)
