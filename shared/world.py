"""World files: the room the simulator builds and the planner maps.

The schema (``deploy/worlds/*.yaml``)::

    name: seed_room
    bounds: [xmin, ymin, xmax, ymax]          # four opaque outer walls on these edges
    walls: [[[x1, y1], [x2, y2]], ...]        # opaque segments: lidar and sonar see them
    glass: [[[x1, y1], [x2, y2]], ...]        # glass: sonar sees it, lidar does not
    boxes: [{pose: [x, y, yaw], size: [w, d]}, ...]
    docks: [{id: home, pose: [x, y, yaw], type: charger}, ...]
    robot: {start: [x, y, yaw]}
    robots: [{name: r1, start: [x, y, yaw]}, ...]   # a fleet in one room (instead of robot)
    aruco_dictionary: DICT_4X4_50             # the docks' marker family (optional)

A world that lists ``robots`` puts them all in one room: the simulator steps them in one physical space,
where they collide with each other and see each other, each under its own namespace (its ``name``).
Without ``robot``, the first of them is also ``robot`` (what single-robot tools read).

A dock may name its ArUco marker: ``marker_id`` (default: the dock's index in ``docks``) and
``marker_size_m`` (the printed square's side, default 0.12 m); see :func:`dock_markers`.

A dock's pose is the robot's base_link pose when docked with contacts mated; the dock body and its
charging plate stand directly ahead of it (see :data:`ROBOT_FRONT_M` and :class:`DockGeometry`).
Keys this version does not know are errors naming the key and the file, as in stack files: a misspelt
``wals:`` would otherwise build a room without its walls.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import msgspec
import numpy as np
from msgspec import Meta

from shared.config_errors import ConfigError, read_yaml_file
from shared.geometry import Pose2D, distances_to_segment
from shared.structs import validate

#: Robot footprint (length along x, width along y) and where base_link sits: at its centre.
ROBOT_LENGTH_M = 0.40
ROBOT_WIDTH_M = 0.30
ROBOT_FRONT_M = ROBOT_LENGTH_M / 2.0

#: How far base_link must stand from any solid for the body to clear it whatever its heading: half the
#: robot's width (the footprint covers that disc), less a centimetre the simulator's placement tolerates.
PLACEMENT_CLEARANCE_M = ROBOT_WIDTH_M / 2.0 - 0.01

Point = tuple[float, float]
Segment = tuple[Point, Point]


def _finite(values: Iterable[float], what: str) -> None:
    values = list(values)
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"{what}: must be finite numbers, got {values}")


class _Strict(msgspec.Struct, forbid_unknown_fields=True, frozen=True, kw_only=True):
    """Every key is validated; an unknown key is an error (``<file>: robot.strat: unknown key``).

    Checks run in ``__post_init__``; a message starts with the field it blames (``pose: ...``)."""


class Box(_Strict, frozen=True):
    pose: tuple[float, float, float]
    size: tuple[float, float]

    def __post_init__(self) -> None:
        _finite(self.pose, "pose")
        _finite(self.size, "size")
        if self.size[0] <= 0 or self.size[1] <= 0:
            raise ValueError(f"size: must be two positive lengths [w, d], got {list(self.size)}")

    def corners(self) -> list[Point]:
        """The four corners in the world frame, counter-clockwise; ``w`` along the box's x axis."""
        w, d = self.size
        frame = Pose2D(*self.pose)
        local = [(-w / 2, -d / 2), (w / 2, -d / 2), (w / 2, d / 2), (-w / 2, d / 2)]
        return [frame.transform_point(px, py) for px, py in local]


class Dock(_Strict, frozen=True):
    id: Annotated[str, Meta(min_length=1)]
    pose: tuple[float, float, float]
    type: str = "charger"
    #: The ArUco marker on the dock's face: its id in the world's dictionary (None: the dock's index).
    marker_id: Annotated[int, Meta(ge=0, le=999)] | None = None
    marker_size_m: Annotated[float, Meta(gt=0.02, le=0.30)] = 0.12

    def __post_init__(self) -> None:
        _finite(self.pose, "pose")

    @property
    def pose2d(self) -> Pose2D:
        return Pose2D.from_seq(self.pose)


#: A fleet robot's name is its namespace: a letter, then letters, digits or underscores.
ROBOT_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}")


class RobotSpec(_Strict, frozen=True):
    #: The robot's namespace (required in ``robots``; the single ``robot`` has none).
    name: str = ""
    start: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: The robot's own patrol waypoints ``[x, y, yaw]`` (a fleet generates some when this is empty).
    patrol: list[tuple[float, float, float]] = msgspec.field(default_factory=list)

    def __post_init__(self) -> None:
        _finite(self.start, "start")
        for i, waypoint in enumerate(self.patrol):
            _finite(waypoint, f"patrol.{i}")


@dataclass(frozen=True)
class DockGeometry:
    """Where a dock's physical parts stand, in the dock pose's frame (x ahead of the docked robot).

    The charging plate's face is at ``x = ROBOT_FRONT_M``: the robot's front touches it when its
    base_link is at the dock pose. The body is a box behind the plate.
    """

    body_depth_m: float = 0.20
    body_width_m: float = 0.40
    #: The marker (ARTag) is on the body's face, centred, facing the robot, its centre this high (at least).
    marker_height_m: float = 0.10
    body_height_m: float = 0.30

    def body_box(self, dock: Dock) -> Box:
        centre = dock.pose2d.compose(Pose2D(ROBOT_FRONT_M + self.body_depth_m / 2, 0.0, 0.0))
        return Box(pose=centre.as_tuple(), size=(self.body_depth_m, self.body_width_m))

    def marker_pose(self, dock: Dock) -> Pose2D:
        """Pose of the marker on the plate's face; its x axis points out of the dock, towards the robot."""
        return dock.pose2d.compose(Pose2D(ROBOT_FRONT_M, 0.0, math.pi))


DOCK_GEOMETRY = DockGeometry()


class World(_Strict, frozen=True):
    name: Annotated[str, Meta(min_length=1)]
    bounds: tuple[float, float, float, float]
    walls: list[Segment] = msgspec.field(default_factory=list)
    glass: list[Segment] = msgspec.field(default_factory=list)
    boxes: list[Box] = msgspec.field(default_factory=list)
    docks: list[Dock] = msgspec.field(default_factory=list)
    #: The single robot; a world that lists ``robots`` and leaves this at its default gets the first of them.
    robot: RobotSpec = msgspec.field(default_factory=RobotSpec)
    robots: list[RobotSpec] = msgspec.field(default_factory=list)
    #: Where robots waiting for a dock stand (``[x, y, yaw]``), out of the docks' approach corridors.
    holding: list[tuple[float, float, float]] = msgspec.field(default_factory=list)
    aruco_dictionary: str = "DICT_4X4_50"

    def __post_init__(self) -> None:
        _finite(self.bounds, "bounds")
        xmin, ymin, xmax, ymax = self.bounds
        if not (xmax > xmin and ymax > ymin):
            raise ValueError(
                "bounds: must be [xmin, ymin, xmax, ymax] with xmax > xmin and ymax > ymin, "
                f"got {list(self.bounds)}"
            )
        for kind in ("walls", "glass"):
            for i, (a, b) in enumerate(getattr(self, kind)):
                _finite((*a, *b), f"{kind}.{i}")
                if math.hypot(b[0] - a[0], b[1] - a[1]) < 1e-6:
                    raise ValueError(f"{kind}.{i}: has zero length: {[list(a), list(b)]}")
        if not re.fullmatch(r"DICT_(4X4|5X5|6X6|7X7)_(50|100|250|1000)", self.aruco_dictionary):
            raise ValueError(
                "aruco_dictionary: must be one of DICT_4X4_50 ... DICT_7X7_1000, "
                f"got {self.aruco_dictionary!r}"
            )
        if self.robots and self.robot == RobotSpec():
            msgspec.structs.force_setattr(self, "robot", RobotSpec(start=self.robots[0].start))
        self._check_fleet()
        self._check_docks()

    def _check_fleet(self) -> None:
        seen: set[str] = set()
        for i, robot in enumerate(self.robots):
            if not ROBOT_NAME.fullmatch(robot.name):
                raise ValueError(
                    f"robots.{i}.name: must be a namespace (a letter, then letters, digits or _), "
                    f"got {robot.name!r}"
                )
            if robot.name in seen:
                raise ValueError(f"robots.{i}.name: {robot.name!r} appears twice in robots")
            seen.add(robot.name)
            if not self.contains(robot.start[0], robot.start[1]):
                raise ValueError(
                    f"robots.{i}.start: ({robot.name}) {list(robot.start[:2])} is outside bounds "
                    f"{list(self.bounds)}"
                )
            for j, waypoint in enumerate(robot.patrol):
                if not self.contains(waypoint[0], waypoint[1]):
                    raise ValueError(
                        f"robots.{i}.patrol.{j}: ({robot.name}) {list(waypoint[:2])} is outside bounds "
                        f"{list(self.bounds)}"
                    )
        for i, pose in enumerate(self.holding):
            _finite(pose, f"holding.{i}")
            if not self.contains(pose[0], pose[1]):
                raise ValueError(f"holding.{i}: {list(pose[:2])} is outside bounds {list(self.bounds)}")

    def _check_docks(self) -> None:
        seen: set[str] = set()
        for i, dock in enumerate(self.docks):
            if dock.id in seen:
                raise ValueError(f"docks.{i}.id: dock id {dock.id!r} appears twice")
            seen.add(dock.id)
            if not self.contains(dock.pose[0], dock.pose[1]):
                raise ValueError(
                    f"docks.{i}.pose: dock {dock.id!r} at {list(dock.pose[:2])} is outside bounds "
                    f"{list(self.bounds)}"
                )
        if not self.contains(self.robot.start[0], self.robot.start[1]):
            raise ValueError(
                f"robot.start: {list(self.robot.start[:2])} is outside bounds {list(self.bounds)}"
            )

    def contains(self, x: float, y: float) -> bool:
        xmin, ymin, xmax, ymax = self.bounds
        return xmin < x < xmax and ymin < y < ymax

    def placement_problem(self, x: float, y: float) -> str | None:
        """Why the robot cannot stand with base_link at ``(x, y)``, or None when it may.

        A cheap check that needs no heading, for a start pose given on a command line before anything
        starts: outside the bounds, or closer to a wall, pane, box or dock body than
        :data:`PLACEMENT_CLEARANCE_M` (the body then overlaps it whatever the heading). The simulator's
        footprint check at the pose's heading stays the exact one.
        """
        if not (math.isfinite(x) and math.isfinite(y)):
            return f"({x}, {y}) is not finite"
        if not self.contains(x, y):
            return f"({x:g}, {y:g}) is outside the bounds {list(self.bounds)}"
        point = np.array([[x, y]])
        segments = [("the outer wall", s) for s in self.boundary_walls()]
        segments += [(f"walls.{i}", s) for i, s in enumerate(self.walls)]
        segments += [(f"glass.{i}", s) for i, s in enumerate(self.glass)]
        for label, (a, b) in segments:
            if distances_to_segment(point, np.array(a), np.array(b))[0] < PLACEMENT_CLEARANCE_M:
                return f"({x:g}, {y:g}) puts the robot into {label}"
        solids = [(f"boxes.{i}", box) for i, box in enumerate(self.boxes)]
        solids += [(f"dock {d.id!r}", DOCK_GEOMETRY.body_box(d)) for d in self.docks]
        for label, box in solids:
            local_x, local_y = Pose2D(*box.pose).inverse().transform_point(x, y)
            gap_x, gap_y = max(abs(local_x) - box.size[0] / 2, 0.0), max(abs(local_y) - box.size[1] / 2, 0.0)
            if math.hypot(gap_x, gap_y) < PLACEMENT_CLEARANCE_M:
                return f"({x:g}, {y:g}) puts the robot into {label}"
        return None

    def boundary_walls(self) -> list[Segment]:
        xmin, ymin, xmax, ymax = self.bounds
        return [
            ((xmin, ymin), (xmax, ymin)),
            ((xmax, ymin), (xmax, ymax)),
            ((xmax, ymax), (xmin, ymax)),
            ((xmin, ymax), (xmin, ymin)),
        ]

    def opaque_segments(self) -> list[Segment]:
        """Every segment the lidar sees: outer walls, inner walls, box edges, dock body edges."""
        segments = self.boundary_walls() + list(self.walls)
        for box in self.boxes + [DOCK_GEOMETRY.body_box(d) for d in self.docks]:
            c = box.corners()
            segments += [(c[i], c[(i + 1) % 4]) for i in range(4)]
        return segments

    def dock(self, dock_id: str) -> Dock:
        for dock in self.docks:
            if dock.id == dock_id:
                return dock
        raise KeyError(f"no dock {dock_id!r} in world {self.name!r} (docks: {[d.id for d in self.docks]})")


@dataclass(frozen=True, slots=True)
class DockMarker:
    """The ArUco marker printed on a dock's face, where perception and the camera agree it is.

    ``pose`` is the marker's centre on the floor plane with its normal (x axis) pointing out of the dock,
    towards an approaching robot; the centre stands ``centre_height_m`` above the floor.
    """

    dock_id: str
    marker_id: int
    size_m: float
    pose: Pose2D
    centre_height_m: float
    dictionary: str


def dock_markers(world: World) -> list[DockMarker]:
    """Every dock's marker; raises :class:`ConfigError` when two docks share a marker id."""
    markers: list[DockMarker] = []
    seen: dict[int, str] = {}
    for i, dock in enumerate(world.docks):
        marker_id = i if dock.marker_id is None else dock.marker_id
        if marker_id in seen:
            raise ConfigError(
                f"world {world.name!r}: docks {seen[marker_id]!r} and {dock.id!r} share marker id {marker_id}"
            )
        seen[marker_id] = dock.id
        centre_height = max(DOCK_GEOMETRY.marker_height_m, dock.marker_size_m / 2 + 0.02)
        markers.append(
            DockMarker(
                dock.id,
                marker_id,
                dock.marker_size_m,
                DOCK_GEOMETRY.marker_pose(dock),
                centre_height,
                world.aruco_dictionary,
            )
        )
    return markers


def parse_world(data: Any, source: str | Path = "<world>") -> World:
    """Validate a decoded world document; raises :class:`ConfigError` naming the file and field."""
    if not isinstance(data, dict):
        raise ConfigError(
            f"{source}: a world file must be a mapping with name, bounds, walls, ...; got {type(data).__name__}"
        )
    return validate(World, data, source)


def world_files(names: Iterable[str | Path]) -> list[Path]:
    """The world files ``names`` give: a file as it is, a directory as every ``*.yaml`` in it (sorted)."""
    files: list[Path] = []
    for name in names:
        path = Path(name)
        files.extend(sorted(path.glob("*.yaml")) if path.is_dir() else [path])
    return files


def load_world(path: str | Path) -> World:
    """Read and validate a world file."""
    return parse_world(read_yaml_file(path, "world file"), Path(path))
