"""The room and the robot as Foxglove scene entities: what the bus never carries but a viewer needs.

The world file gives walls (dark), glass (translucent blue: the lidar sees through it, the sonar does
not), boxes, each dock's body (green) with its dock pose and its staging pose (where navigation hands
over to the docking controller). The robot's footprint is an entity locked to ``base_link``, so it
follows the transforms.
"""

from __future__ import annotations

import math

from foxglove import messages as fg

from shared.foxglove_view.encoding import ViewMessage, protobuf_view, timestamp_from_ns
from shared.geometry import Pose2D
from shared.topics import BASE_FRAME, MAP_FRAME
from shared.world import DOCK_GEOMETRY, ROBOT_LENGTH_M, ROBOT_WIDTH_M, Segment, World

#: Where the docking service stages by default: straight behind the dock (its graceful approach).
DEFAULT_STAGING_OFFSET_M = 0.7

WALL_COLOR = fg.Color(r=0.15, g=0.15, b=0.15, a=1.0)
GLASS_COLOR = fg.Color(r=0.55, g=0.8, b=1.0, a=0.35)
BOX_COLOR = fg.Color(r=0.55, g=0.45, b=0.35, a=1.0)
DOCK_COLOR = fg.Color(r=0.1, g=0.7, b=0.2, a=1.0)
STAGING_COLOR = fg.Color(r=1.0, g=0.6, b=0.0, a=1.0)
ROBOT_COLOR = fg.Color(r=0.2, g=0.4, b=0.9, a=0.85)
LABEL_COLOR = fg.Color(r=1.0, g=1.0, b=1.0, a=1.0)

WALL_THICKNESS_M = 0.05
WALL_HEIGHT_M = 0.4
GLASS_HEIGHT_M = 0.6
BOX_HEIGHT_M = 0.3
DOCK_HEIGHT_M = 0.25
ROBOT_HEIGHT_M = 0.12


def _pose(x: float, y: float, z: float, yaw_rad: float) -> fg.Pose:
    return fg.Pose(
        position=fg.Vector3(x=x, y=y, z=z),
        orientation=fg.Quaternion(x=0.0, y=0.0, z=math.sin(yaw_rad / 2.0), w=math.cos(yaw_rad / 2.0)),
    )


def _segment_cube(segment: Segment, thickness_m: float, height_m: float, color: fg.Color) -> fg.CubePrimitive:
    (x1, y1), (x2, y2) = segment
    length = math.hypot(x2 - x1, y2 - y1)
    return fg.CubePrimitive(
        pose=_pose((x1 + x2) / 2.0, (y1 + y2) / 2.0, height_m / 2.0, math.atan2(y2 - y1, x2 - x1)),
        size=fg.Vector3(x=length + thickness_m, y=thickness_m, z=height_m),
        color=color,
    )


def _arrow(pose: Pose2D, color: fg.Color, length_m: float = 0.3) -> fg.ArrowPrimitive:
    return fg.ArrowPrimitive(
        pose=_pose(pose.x, pose.y, 0.02, pose.yaw),
        shaft_length=length_m * 0.7,
        shaft_diameter=0.03,
        head_length=length_m * 0.3,
        head_diameter=0.08,
        color=color,
    )


def _label(x: float, y: float, text: str) -> fg.TextPrimitive:
    return fg.TextPrimitive(
        pose=_pose(x, y, 0.5, 0.0),
        billboard=True,
        font_size=14.0,
        scale_invariant=True,
        color=LABEL_COLOR,
        text=text,
    )


def staging_pose(dock_pose: Pose2D, staging_offset_m: float = DEFAULT_STAGING_OFFSET_M) -> Pose2D:
    """Straight behind the dock, facing it (the docking service's graceful staging pose)."""
    return dock_pose.compose(Pose2D(-staging_offset_m, 0.0, 0.0))


def world_entities(
    world: World, stamp_ns: int = 0, staging_offset_m: float = DEFAULT_STAGING_OFFSET_M
) -> list[fg.SceneEntity]:
    """Walls, glass, boxes and docks of ``world`` in the map frame (ids stable, so updates replace)."""
    ts = timestamp_from_ns(stamp_ns)

    def entity(
        entity_id: str,
        cubes: list[fg.CubePrimitive] | None = None,
        arrows: list[fg.ArrowPrimitive] | None = None,
        texts: list[fg.TextPrimitive] | None = None,
    ) -> fg.SceneEntity:
        return fg.SceneEntity(
            timestamp=ts,
            frame_id=MAP_FRAME,
            id=entity_id,
            frame_locked=True,
            cubes=cubes,
            arrows=arrows,
            texts=texts,
        )

    walls = [
        _segment_cube(s, WALL_THICKNESS_M, WALL_HEIGHT_M, WALL_COLOR)
        for s in world.boundary_walls() + world.walls
    ]
    glass = [_segment_cube(s, WALL_THICKNESS_M, GLASS_HEIGHT_M, GLASS_COLOR) for s in world.glass]
    boxes = [
        fg.CubePrimitive(
            pose=_pose(b.pose[0], b.pose[1], BOX_HEIGHT_M / 2.0, b.pose[2]),
            size=fg.Vector3(x=b.size[0], y=b.size[1], z=BOX_HEIGHT_M),
            color=BOX_COLOR,
        )
        for b in world.boxes
    ]
    entities = [entity("walls", cubes=walls), entity("glass", cubes=glass), entity("boxes", cubes=boxes)]
    for dock in world.docks:
        body = DOCK_GEOMETRY.body_box(dock)
        cube = fg.CubePrimitive(
            pose=_pose(body.pose[0], body.pose[1], DOCK_HEIGHT_M / 2.0, body.pose[2]),
            size=fg.Vector3(x=body.size[0], y=body.size[1], z=DOCK_HEIGHT_M),
            color=DOCK_COLOR,
        )
        staging = staging_pose(dock.pose2d, staging_offset_m)
        entities.append(
            entity(
                f"dock/{dock.id}",
                cubes=[cube],
                arrows=[_arrow(dock.pose2d, DOCK_COLOR)],
                texts=[_label(dock.pose[0], dock.pose[1], f"dock {dock.id}")],
            )
        )
        entities.append(
            entity(
                f"staging/{dock.id}",
                arrows=[_arrow(staging, STAGING_COLOR)],
                texts=[_label(staging.x, staging.y, f"staging {dock.id}")],
            )
        )
    return entities


def world_scene(
    topic: str, world: World, stamp_ns: int = 0, staging_offset_m: float = DEFAULT_STAGING_OFFSET_M
) -> ViewMessage:
    return protobuf_view(
        topic, fg.SceneUpdate(entities=world_entities(world, stamp_ns, staging_offset_m)), stamp_ns
    )


def robot_scene(topic: str, stamp_ns: int = 0, frame_id: str = BASE_FRAME) -> ViewMessage:
    """The robot's footprint and heading, locked to its base frame."""
    body = fg.CubePrimitive(
        pose=_pose(0.0, 0.0, ROBOT_HEIGHT_M / 2.0, 0.0),
        size=fg.Vector3(x=ROBOT_LENGTH_M, y=ROBOT_WIDTH_M, z=ROBOT_HEIGHT_M),
        color=ROBOT_COLOR,
    )
    heading = fg.ArrowPrimitive(
        pose=_pose(0.0, 0.0, ROBOT_HEIGHT_M + 0.01, 0.0),
        shaft_length=0.2,
        shaft_diameter=0.03,
        head_length=0.08,
        head_diameter=0.08,
        color=LABEL_COLOR,
    )
    entity = fg.SceneEntity(
        timestamp=timestamp_from_ns(stamp_ns),
        frame_id=frame_id,
        id="robot",
        frame_locked=True,
        cubes=[body],
        arrows=[heading],
    )
    return protobuf_view(topic, fg.SceneUpdate(entities=[entity]), stamp_ns)
