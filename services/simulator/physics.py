"""The simulated room and the robots in it: a :class:`Room` (a pymunk space with the world's walls, glass,
boxes and docks) and each :class:`Robot` (its body, drive, odometry, sensors and collision events).

The room owns the space and hands each contact to the robot whose body made it (:meth:`Robot.touched`,
:meth:`Robot.touched_robot`, :meth:`Robot.parted`); a robot asks its room what its body overlaps and what
its sensors see (:meth:`Room.overlapping`, :meth:`Room.with_others`). Neither reaches into the other.

Several robots can share one room (a fleet, :meth:`Robot.join`): one space, so they collide with
each other, and each one's lidar, sonar, camera detections and infrared see the others' bodies. They
are stepped together (:func:`step_together`); a robot alone in its room steps itself.

The robot is a dynamic box whose velocity is set every step from the limited diff-drive twist (forward
along its heading, no sideways slip), then pymunk's contact solver stops it at whatever it drives into.
Every obstacle is solid, glass included. The space steps at a fixed ``dt_s``; nothing here knows about
wall-clock time or the bus (Chipmunk2D, the engine under pymunk, is described at chipmunk-physics.net).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pymunk

from services.simulator import sensors
from services.simulator.localisation import believed_pose, map_to_odom, scan_agreement
from services.simulator.odometry import Odometry
from services.simulator.robot_model import DiffDrive, DiffDriveParams, Twist2D
from shared.geometry import Pose2D, wrap_angle
from shared.models import infrared
from shared.models.dock_contact import DockContact, DockContactParams, dock_contact
from shared.models.footprint import footprint_corners, separated
from shared.models.raycast import SegmentSet, cast_rays
from shared.world import DOCK_GEOMETRY, ROBOT_FRONT_M, Dock, World

ROBOT_COLLISION_TYPE = 1
OBSTACLE_COLLISION_TYPE = 2
#: What a robot can run into; "robot" is another robot in the same room (the event names it).
COLLISION_KINDS = ("wall", "glass", "box", "dock", "robot")


class PoseInCollisionError(ValueError):
    """A requested robot pose overlaps an obstacle or lies outside the room."""


@dataclass(frozen=True, slots=True)
class SimParams:
    """Everything about the simulation that is not the room or the drive."""

    dt_s: float = 0.01
    #: Relative std dev of each wheel's travel per step seen by odometry (0: odometry follows the truth).
    odom_noise: float = 0.0
    seed: int = 0
    lidar: sensors.LidarParams = field(default_factory=sensors.LidarParams)
    ultrasonic: sensors.UltrasonicParams = field(default_factory=sensors.UltrasonicParams)
    camera: sensors.FiducialCameraParams = field(default_factory=sensors.FiducialCameraParams)
    infrared: infrared.InfraredParams = field(default_factory=infrared.InfraredParams)
    contact: DockContactParams = field(default_factory=DockContactParams)
    #: Localisation error (in base_link) of the simulated localiser; see services.simulator.localisation.
    localisation_error: Pose2D = field(default_factory=Pose2D)
    #: A touch on the dock's plate is docking, not a collision, if the robot is within this heading of the
    #: dock or slower than ``dock_gentle_speed_mps`` at the contact point.
    dock_align_tolerance_rad: float = 0.35
    dock_gentle_speed_mps: float = 0.10
    #: A contact with the same obstacle that begins again within this time of ending is the same collision.
    collision_debounce_s: float = 0.2
    #: Penetration tolerated when placing the robot (teleport).
    placement_tolerance_m: float = 0.001
    friction: float = 0.3

    def __post_init__(self) -> None:
        if not (math.isfinite(self.dt_s) and 0.0 < self.dt_s <= 0.05):
            raise ValueError(f"SimParams.dt_s must be in (0, 0.05] s, got {self.dt_s!r}")
        for name in (
            "odom_noise",
            "dock_align_tolerance_rad",
            "dock_gentle_speed_mps",
            "collision_debounce_s",
            "placement_tolerance_m",
            "friction",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"SimParams.{name} must be >= 0, got {value!r}")


@dataclass(frozen=True, slots=True)
class CollisionEvent:
    """The robot started touching an obstacle it should not have touched.

    ``kind`` is one of :data:`COLLISION_KINDS`; ``dock_id`` is set for "dock"; ``speed_mps`` is the speed
    of the robot's contact point as the contact began; ``x_m``, ``y_m`` locate the contact in the map.
    """

    kind: str
    time_s: float
    x_m: float
    y_m: float
    speed_mps: float
    dock_id: str | None = None
    #: For kind "robot": the other robot's name.
    other_robot: str | None = None


@dataclass(frozen=True, slots=True)
class _Obstacle:
    kind: str
    dock: Dock | None = None


def _contact_centre(
    points: Sequence[pymunk.ContactPoint], fallback: tuple[float, float]
) -> tuple[float, float]:
    """The mean of a contact's points (each midway between the two shapes), or ``fallback`` without any."""
    if not points:
        return fallback
    cx = sum(0.5 * (p.point_a.x + p.point_b.x) for p in points) / len(points)
    cy = sum(0.5 * (p.point_a.y + p.point_b.y) for p in points) / len(points)
    return cx, cy


def _sinc(x: float) -> float:
    return 1.0 - x * x / 6.0 if abs(x) < 1e-4 else math.sin(x) / x


class _RobotEdges:
    """The footprint edges of every robot in one room, as the sensors of each see the others.

    Every sensor reading of every robot asks for them, so they are built once per move (a step or a
    teleport), not once per reading (measurement 67).
    """

    __slots__ = ("_edges", "_sets")

    def __init__(self) -> None:
        #: Every robot's four edges in room order, ``(start, delta)`` each ``(4N, 2)``; None once stale.
        self._edges: tuple[np.ndarray, np.ndarray] | None = None
        #: Each robot's segments plus the others', by (robot, segments), while the edges stand.
        self._sets: dict[tuple[int, int], SegmentSet] = {}

    def moved(self) -> None:
        """A robot of the room moved (or joined): what was built from the edges is stale."""
        self._edges = None
        self._sets.clear()

    def with_others(self, robot: Robot, segments: SegmentSet) -> SegmentSet:
        """``segments`` plus the edges of every robot in ``robot``'s room but ``robot`` (in room order)."""
        key = (id(robot), id(segments))
        found = self._sets.get(key)
        if found is None:
            members = robot.room.members
            if self._edges is None:
                corners = np.stack([m.footprint() for m in members])  # (N, 4, 2), counter-clockwise
                self._edges = corners.reshape(-1, 2), (np.roll(corners, -1, axis=1) - corners).reshape(-1, 2)
            start, delta = self._edges
            i = members.index(robot)
            own = slice(4 * i, 4 * i + 4)
            others = SegmentSet.from_arrays(np.delete(start, own, axis=0), np.delete(delta, own, axis=0))
            found = self._sets[key] = SegmentSet.concat(segments, others)
        return found


class Room:
    """One world's room in a physics space: its walls, glass, boxes and docks, and the robots in it.

    Contacts are handed to the robot whose body made them; see the module docstring.
    """

    def __init__(self, world: World, friction: float = 0.3) -> None:
        self.world = world
        self.friction = friction
        self._obstacles: dict[pymunk.Shape, _Obstacle] = {}
        #: (label, outline) of every obstacle, for placement checks: segments as 2 points, boxes as 4.
        self._outlines: list[tuple[str, np.ndarray]] = []
        self.opaque = SegmentSet(world.opaque_segments())
        self.glass = SegmentSet(world.glass)
        self.sonar_visible = SegmentSet.concat(self.opaque, self.glass)
        self.space = pymunk.Space()
        self.space.gravity = (0.0, 0.0)
        # Pymunk's defaults suit pixels; the room is in metres.
        self.space.collision_slop = 0.0005
        self.space.iterations = 10
        #: Every robot in this room, and whose each robot shape is (a teleport makes a new shape).
        self.members: list[Robot] = []
        self._by_shape: dict[pymunk.Shape, Robot] = {}
        self._robot_edges = _RobotEdges()
        self._add_obstacles()
        self.space.on_collision(
            ROBOT_COLLISION_TYPE,
            OBSTACLE_COLLISION_TYPE,
            begin=self._obstacle_begin,
            separate=self._obstacle_separate,
        )
        self.space.on_collision(
            ROBOT_COLLISION_TYPE,
            ROBOT_COLLISION_TYPE,
            begin=self._robots_begin,
            separate=self._robots_separate,
        )

    # ----------------------------------------------------------------------------------------- building
    def _add_static(
        self, shape: pymunk.Shape, obstacle: _Obstacle, outline: list[tuple[float, float]]
    ) -> None:
        label = obstacle.kind if obstacle.dock is None else f"dock {obstacle.dock.id!r}"
        self._outlines.append((label, np.asarray(outline, dtype=float)))
        shape.collision_type = OBSTACLE_COLLISION_TYPE
        shape.friction = self.friction
        shape.elasticity = 0.0
        self.space.add(shape)
        self._obstacles[shape] = obstacle

    def _add_obstacles(self) -> None:
        static = self.space.static_body
        for a, b in self.world.boundary_walls() + list(self.world.walls):
            self._add_static(pymunk.Segment(static, a, b, 0.0), _Obstacle("wall"), [a, b])
        for a, b in self.world.glass:
            self._add_static(pymunk.Segment(static, a, b, 0.0), _Obstacle("glass"), [a, b])
        for box in self.world.boxes:
            self._add_static(pymunk.Poly(static, box.corners()), _Obstacle("box"), box.corners())
        for dock in self.world.docks:
            corners = DOCK_GEOMETRY.body_box(dock).corners()
            self._add_static(pymunk.Poly(static, corners), _Obstacle("dock", dock), corners)

    # ----------------------------------------------------------------------------------------- robots
    def admit(self, robot: Robot) -> None:
        """``robot`` joins the room (its body is placed with :meth:`place`)."""
        if any(m.name == robot.name for m in self.members):
            raise ValueError(f"a robot named {robot.name!r} is already in this room")
        self.members.append(robot)

    def place(self, robot: Robot, body: pymunk.Body, shape: pymunk.Shape) -> None:
        """Put ``robot``'s (new) body in the space."""
        self.space.add(body, shape)
        self._by_shape[shape] = robot
        self._robot_edges.moved()

    def remove(self, body: pymunk.Body, shape: pymunk.Shape) -> None:
        """Take a robot's (old) body out of the space."""
        self.space.remove(body, shape)
        del self._by_shape[shape]
        self._robot_edges.moved()

    def moved(self) -> None:
        """A robot moved: what its sensors see of it is stale."""
        self._robot_edges.moved()

    def others(self, robot: Robot) -> list[Robot]:
        return [m for m in self.members if m is not robot]

    def obstacle(self, shape: pymunk.Shape) -> _Obstacle | None:
        """The obstacle ``shape`` is, or None (a robot)."""
        return self._obstacles.get(shape)

    def overlapping(self, footprint: np.ndarray, robot: Robot) -> list[str]:
        """What ``footprint`` overlaps: obstacles, and the robots in the room other than ``robot``."""
        found = [label for label, outline in self._outlines if not separated(footprint, outline)]
        for other in self.others(robot):
            if not separated(footprint, other.footprint()):
                found.append(f"robot {other.name!r}")
        return found

    def with_others(self, robot: Robot, segments: SegmentSet) -> SegmentSet:
        """``segments`` plus the edges of every other robot in the room (what ``robot``'s sensors see)."""
        if len(self.members) < 2:
            return segments
        return self._robot_edges.with_others(robot, segments)

    # ----------------------------------------------------------------------------------------- contacts
    def _robot_of(self, arbiter: pymunk.Arbiter) -> Robot | None:
        first, second = arbiter.shapes
        return self._by_shape.get(first) or self._by_shape.get(second)

    def _obstacle_begin(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        robot = self._robot_of(arbiter)
        if robot is not None:
            robot.touched(arbiter)

    def _obstacle_separate(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        robot = self._robot_of(arbiter)
        if robot is not None:
            robot.parted(arbiter)

    def _robots_begin(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        """Two robots touched: each records a collision naming the other, at the same point."""
        first, second = (self._by_shape.get(shape) for shape in arbiter.shapes)
        if first is None or second is None:
            return
        (ax, ay), (bx, by) = first.body.position, second.body.position
        cx, cy = _contact_centre(arbiter.contact_point_set.points, (0.5 * (ax + bx), 0.5 * (ay + by)))
        for robot, other in ((first, second), (second, first)):
            speed = float(
                abs(
                    robot.body.velocity_at_world_point((cx, cy))
                    - other.body.velocity_at_world_point((cx, cy))
                )
            )
            robot.touched_robot(other, float(cx), float(cy), speed)

    def _robots_separate(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        first, second = (self._by_shape.get(shape) for shape in arbiter.shapes)
        if first is not None and second is not None:
            first.parted_from(second.shape)
            second.parted_from(first.shape)


class Robot:
    """One robot in a :class:`Room`, stepped at a fixed rate. Public methods are the simulator service's API.

    Not thread-safe: step it and read its sensors from one thread.
    """

    def __init__(
        self,
        world: World,
        drive: DiffDriveParams | None = None,
        params: SimParams | None = None,
        *,
        start: Pose2D | None = None,
        name: str = "",
        room: Room | None = None,
    ):
        """A robot at ``start`` (default: the world's ``robot.start``) in a room of its own, or in ``room``
        as ``name``: use :meth:`join` for that."""
        self.world = world
        self.name = name
        self.params = params or SimParams()
        self.drive = DiffDrive(drive)
        # Separate streams: how often sensors are read does not change the odometry's noise.
        sensor_seed, odom_seed = np.random.SeedSequence(self.params.seed).spawn(2)
        self.rng = np.random.default_rng(sensor_seed)
        self.odometry = Odometry(self.drive.params, self.params.odom_noise, np.random.default_rng(odom_seed))
        self.time_s = 0.0
        self.steps = 0
        self.collision_counts = dict.fromkeys(COLLISION_KINDS, 0)
        self.twist = Twist2D()  # measured body twist of the last step
        self._events: list[CollisionEvent] = []
        self._last_separation_s: dict[pymunk.Shape, float] = {}
        if room is not None and room.world is not world:
            raise ValueError("robots share a room only in the same world")
        self.room = room if room is not None else Room(world, self.params.friction)
        self.room.admit(self)
        pose = start if start is not None else Pose2D.from_seq(world.robot.start)
        try:
            self._check_placement(pose, f"{name} start" if name else "robot.start")
        except PoseInCollisionError:
            self.room.members.remove(self)
            raise
        self.body, self.shape = self._new_robot(pose)

    def join(
        self, name: str, start: Pose2D, params: SimParams | None = None, drive: DiffDriveParams | None = None
    ) -> Robot:
        """Another robot, ``name``, in this robot's room at ``start``: the same space and obstacles."""
        return Robot(
            self.world,
            drive or self.drive.params,
            params or self.params,
            start=start,
            name=name,
            room=self.room,
        )

    @property
    def members(self) -> list[Robot]:
        """Every robot in this robot's room (itself included), in the order they came."""
        return self.room.members

    @property
    def space(self) -> pymunk.Space:
        return self.room.space

    @property
    def opaque(self) -> SegmentSet:
        return self.room.opaque

    @property
    def shares_room(self) -> bool:
        return len(self.room.members) > 1

    def _new_robot(self, pose: Pose2D) -> tuple[pymunk.Body, pymunk.Poly]:
        """The robot's body at ``pose``, added to the room, standing still."""
        p = self.drive.params
        size = (p.footprint_length_m, p.footprint_width_m)
        body = pymunk.Body(p.mass_kg, pymunk.moment_for_box(p.mass_kg, size))
        body.position = (pose.x, pose.y)
        body.angle = pose.yaw
        body.velocity_func = self._drive_velocity
        shape = pymunk.Poly.create_box(body, size, radius=0.0)
        shape.collision_type = ROBOT_COLLISION_TYPE
        shape.friction = self.params.friction
        shape.elasticity = 0.0
        self.room.place(self, body, shape)
        return body, shape

    def _drive_velocity(self, body: pymunk.Body, gravity: object, damping: float, dt: float) -> None:
        """Pymunk's velocity phase: the wheels impose the delivered twist, then the solver resolves contacts.

        Chipmunk integrates positions at the start of the next step with the solved velocity, moving the
        body in a straight line; aiming that chord along the arc the twist describes keeps free motion exact.
        """
        twist = self.drive.delivered
        turn = twist.angular_radps * dt
        chord_speed = twist.linear_mps * _sinc(0.5 * turn)
        mid = body.angle + 0.5 * turn
        body.velocity = (chord_speed * math.cos(mid), chord_speed * math.sin(mid))
        body.angular_velocity = twist.angular_radps

    # ----------------------------------------------------------------------------------------- state
    @property
    def pose(self) -> Pose2D:
        """Ground-truth base_link pose in the map."""
        x, y = self.body.position
        return Pose2D(float(x), float(y), wrap_angle(float(self.body.angle)))

    @property
    def odom_pose(self) -> Pose2D:
        """odom -> base_link from wheel odometry."""
        return self.odometry.pose

    def believe(self, belief: Pose2D) -> None:
        """Make the simulated localiser believe the robot stands at ``belief`` in the map (an initial pose
        given to a localiser); the offset from the truth is its localisation error from now on."""
        self.params = replace(self.params, localisation_error=self.pose.inverse().compose(belief))

    def believed_pose(self) -> Pose2D:
        """Where the simulated localiser believes the robot stands in the map."""
        return believed_pose(self.pose, self.params.localisation_error)

    def map_to_odom(self) -> Pose2D:
        """The map -> odom transform of the simulated localiser (with the configured error)."""
        return map_to_odom(self.pose, self.odometry.pose, self.params.localisation_error)

    def overlapping_obstacles(self, pose: Pose2D) -> list[str]:
        """What the robot's footprint would overlap at ``pose`` by more than ``placement_tolerance_m``
        (obstacles, and the other robots in the room)."""
        p, inset = self.drive.params, 2.0 * self.params.placement_tolerance_m
        footprint = footprint_corners(pose, p.footprint_length_m - inset, p.footprint_width_m - inset)
        return self.room.overlapping(footprint, self)

    def footprint(self) -> np.ndarray:
        """The robot's footprint where it stands, ``(4, 2)`` counter-clockwise."""
        p = self.drive.params
        return footprint_corners(self.pose, p.footprint_length_m, p.footprint_width_m)

    def other_footprints(self) -> list[np.ndarray]:
        """The footprints of the other robots in the room (what the camera draws of them)."""
        return [other.footprint() for other in self.room.others(self)]

    def _with_others(self, segments: SegmentSet) -> SegmentSet:
        """``segments`` plus the edges of every other robot in the room (what sensors see of them)."""
        return self.room.with_others(self, segments)

    def _check_placement(self, pose: Pose2D, what: str) -> None:
        if not all(math.isfinite(v) for v in pose.as_tuple()):
            raise PoseInCollisionError(f"{what} {pose.as_tuple()} is not finite")
        if not self.world.contains(pose.x, pose.y):
            raise PoseInCollisionError(
                f"{what} ({pose.x:.3f}, {pose.y:.3f}) is outside the room bounds {list(self.world.bounds)}"
            )
        overlaps = self.overlapping_obstacles(pose)
        if overlaps:
            raise PoseInCollisionError(
                f"{what} ({pose.x:.3f}, {pose.y:.3f}, {pose.yaw:.3f}) puts the robot into "
                + ", ".join(overlaps)
            )

    def teleport(self, pose: Pose2D) -> None:
        """Place the robot at ``pose``, standing still, and restart odometry there.

        Raises :class:`PoseInCollisionError` if base_link is outside the room or the footprint overlaps
        anything; the robot then stays where it was.
        """
        self._check_placement(pose, "pose")
        # A fresh body carries no velocity or solver state (penetration bias) over from the old place.
        self.room.remove(self.body, self.shape)
        self.body, self.shape = self._new_robot(pose)
        self.drive.stop()
        self.odometry.reset()
        self.twist = Twist2D()

    # ----------------------------------------------------------------------------------------- stepping
    def step(self, cmd_v: float, cmd_w: float) -> None:
        """Advance one ``dt_s`` with the base commanded to ``cmd_v`` (m/s) and ``cmd_w`` (rad/s).

        The motion of a step follows the twist set in the previous step (pymunk integrates positions
        before velocities), so the base answers a command one step (``dt_s``) later.
        """
        if self.shares_room:
            raise RuntimeError("robots that share a room step together: use step_together")
        before = self._drive_step(cmd_v, cmd_w)
        self.space.step(self.params.dt_s)
        self._after_step(before)

    def _drive_step(self, cmd_v: float, cmd_w: float) -> tuple[float, float, float]:
        """The base answers the command; returns where the body stood before the space steps."""
        self.drive.step(Twist2D(cmd_v, cmd_w), self.params.dt_s)
        x0, y0 = self.body.position
        return float(x0), float(y0), float(self.body.angle)

    def _after_step(self, before: tuple[float, float, float]) -> None:
        dt = self.params.dt_s
        x0, y0, yaw0 = before
        self.room.moved()
        self.steps += 1
        self.time_s = self.steps * dt
        # What the wheels rolled: the displacement along the heading, not any sideways push by a contact.
        dx, dy = self.body.position[0] - x0, self.body.position[1] - y0
        turned = float(self.body.angle) - yaw0
        mid = yaw0 + 0.5 * turned
        travelled = (dx * math.cos(mid) + dy * math.sin(mid)) / _sinc(0.5 * turned)
        self.twist = Twist2D(travelled / dt, turned / dt)
        self.odometry.update(self.twist, dt)

    # ----------------------------------------------------------------------------------------- collisions
    def touched_robot(self, other: Robot, x_m: float, y_m: float, speed_mps: float) -> None:
        """Another robot of the room touched this one at ``(x_m, y_m)``: a collision naming it."""
        last = self._last_separation_s.get(other.shape)
        if last is not None and self.time_s - last < self.params.collision_debounce_s:
            return
        self.collision_counts["robot"] += 1
        self._events.append(
            CollisionEvent(
                kind="robot",
                time_s=self.time_s,
                x_m=x_m,
                y_m=y_m,
                speed_mps=speed_mps,
                other_robot=other.name,
            )
        )

    def parted_from(self, shape: pymunk.Shape) -> None:
        """The contact with ``shape`` (an obstacle's or another robot's) ended now."""
        self._last_separation_s[shape] = self.time_s

    def touched(self, arbiter: pymunk.Arbiter) -> None:
        """This robot's body began touching an obstacle: a collision, unless it is docking."""
        robot_shape, other = arbiter.shapes
        if robot_shape is not self.shape:
            robot_shape, other = other, robot_shape
        obstacle = self.room.obstacle(other)
        if obstacle is None:
            return
        last = self._last_separation_s.get(other)
        if last is not None and self.time_s - last < self.params.collision_debounce_s:
            return
        points = arbiter.contact_point_set.points
        cx, cy = _contact_centre(points, (self.body.position.x, self.body.position.y))
        speed = float(abs(self.body.velocity_at_world_point((cx, cy))))
        if obstacle.dock is not None and self._is_docking_touch(obstacle.dock, points, speed):
            return
        self.collision_counts[obstacle.kind] += 1
        self._events.append(
            CollisionEvent(
                kind=obstacle.kind,
                time_s=self.time_s,
                x_m=float(cx),
                y_m=float(cy),
                speed_mps=speed,
                dock_id=obstacle.dock.id if obstacle.dock is not None else None,
            )
        )

    def parted(self, arbiter: pymunk.Arbiter) -> None:
        """This robot's body stopped touching an obstacle."""
        for shape in arbiter.shapes:
            if self.room.obstacle(shape) is not None:
                self.parted_from(shape)

    def _is_docking_touch(self, dock: Dock, points: Sequence[pymunk.ContactPoint], speed_mps: float) -> bool:
        """A touch on the charging plate, square to the dock or gentle, is docking rather than a crash."""
        frame = dock.pose2d
        half_width = 0.5 * DOCK_GEOMETRY.body_width_m
        for p in points:
            local = Pose2D(0.5 * (p.point_a.x + p.point_b.x), 0.5 * (p.point_a.y + p.point_b.y)).relative_to(
                frame
            )
            if abs(local.x - ROBOT_FRONT_M) > 0.01 or abs(local.y) > half_width + 0.01:
                return False
        aligned = abs(wrap_angle(float(self.body.angle) - frame.yaw)) <= self.params.dock_align_tolerance_rad
        return aligned or speed_mps <= self.params.dock_gentle_speed_mps

    def drain_collisions(self) -> list[CollisionEvent]:
        """Collision events since the last call, oldest first (the caller publishes them)."""
        events, self._events = self._events, []
        return events

    # ----------------------------------------------------------------------------------------- sensors
    def lidar_scan(self, pose: Pose2D | None = None) -> sensors.LidarScan:
        """A lidar scan from ``pose`` (default: the robot's true pose); sees opaque surfaces, not glass."""
        at = self.pose if pose is None else pose
        return sensors.lidar_scan(at, self._with_others(self.room.opaque), self.params.lidar, self.rng)

    def lidar_agreement(self, estimate: Pose2D) -> float:
        """How well the map seen from ``estimate`` agrees with what the lidar sees from the true pose
        (:func:`~services.simulator.localisation.scan_agreement`; noise left out of both)."""
        params = self.params.lidar
        segments = self._with_others(self.room.opaque)

        def cast(pose: Pose2D) -> np.ndarray:
            sensor = pose.compose(params.mount)
            ranges = cast_rays((sensor.x, sensor.y), sensor.yaw + params.beam_angles_rad(), segments)
            return np.where((ranges >= params.range_min_m) & (ranges <= params.range_max_m), ranges, np.inf)

        return scan_agreement(cast(self.pose), cast(estimate))

    def ultrasonic_range(self, pose: Pose2D | None = None) -> float:
        """The front ultrasonic reading from ``pose`` (default: true pose); sees opaque surfaces and glass."""
        at = self.pose if pose is None else pose
        return sensors.ultrasonic_range(
            at, self._with_others(self.room.sonar_visible), self.params.ultrasonic, self.rng
        )

    def dock_infrared(self, pose: Pose2D | None = None) -> tuple[int, int, int]:
        """The right, central and left infrared receivers' readings from ``pose`` (default: true pose)."""
        at = self.pose if pose is None else pose
        return infrared.receiver_readings(
            at, self.world.docks, self._with_others(self.room.opaque), self.params.infrared, self.rng
        )

    def detect_docks(self, pose: Pose2D | None = None) -> list[sensors.DockDetection]:
        """Every dock the camera reads from ``pose`` (default: true pose), nearest first; glass hides none."""
        at = self.pose if pose is None else pose
        return sensors.detect_docks(
            at, self.world.docks, self._with_others(self.room.opaque), self.params.camera, self.rng
        )

    def detect_dock(
        self, pose: Pose2D | None = None, dock_id: str | None = None
    ) -> sensors.DockDetection | None:
        """The nearest visible dock (or the one named ``dock_id``), None if the camera reads no marker.

        The result's ``dock_pose_in_base`` is the dock pose (base_link's pose when docked) in base_link.
        """
        for detection in self.detect_docks(pose):
            if dock_id is None or detection.dock_id == dock_id:
                return detection
        return None

    def dock_contact(self) -> DockContact:
        """Ground-truth contact state against the nearest dock."""
        return dock_contact(self.pose, self.world.docks, self.params.contact)


def step_together(robots: Sequence[Robot], commands: Sequence[tuple[float, float]]) -> None:
    """One ``dt_s`` for every robot in one room, each commanded ``(v, w)``: one step of their shared space."""
    if not robots:
        return
    if len(commands) != len(robots):
        raise ValueError(f"{len(robots)} robots but {len(commands)} commands")
    room = robots[0].room
    if any(r.room is not room for r in robots) or len(robots) != len(room.members):
        raise ValueError("step_together steps every robot of one room, and only them")
    before = [r._drive_step(v, w) for r, (v, w) in zip(robots, commands)]
    room.space.step(robots[0].params.dt_s)
    for robot, start in zip(robots, before):
        robot._after_step(start)
