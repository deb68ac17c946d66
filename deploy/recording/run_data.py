"""A recording's run as plain data for :mod:`deploy.plotting`.

From one robot's keys (its namespace): ``ground_truth_pose`` for the driven trajectory (the localiser's
``map_to_base_link_pose2d`` when there is no ground truth), every distinct non-empty ``plan``, ``battery_status``,
the last ``map`` (drawn when there is no world file), and sonar echoes: each ``ultrasonic`` reading with
the sensor's pose when it listened (the robot's pose at the reading's stamp and the sensor's mount from
``tf_static``), drawn as the arc at its range across the cone. Times on the plot are seconds since the
recording started.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from deploy.plotting import MapImage, RunPicture
from deploy.recording.reading import RawMessage, Recording
from shared import topics
from shared.geometry import Pose2D
from shared.messages import (
    BatteryState,
    Float64MultiArray,
    OccupancyGrid,
    Path,
    PoseStamped,
    Range,
    TFMessage,
)
from shared.names import topic_key
from shared.schema import MessageError
from shared.world import World


@dataclass
class _Collected:
    """Series gathered in one pass over the recording."""

    truth: list[tuple[float, float, float, float, float]] = field(
        default_factory=list
    )  # t_log, stamp, x, y, yaw
    believed: list[tuple[float, float, float, float]] = field(default_factory=list)  # t_log, x, y, yaw
    plans: list[np.ndarray] = field(default_factory=list)
    battery: list[tuple[float, float]] = field(default_factory=list)
    ranges: list[tuple[float, float, float]] = field(
        default_factory=list
    )  # stamp, range, field of view (echoes)
    mount: Pose2D | None = None
    last_map: OccupancyGrid | None = None


def _valid_echo(msg: Range) -> bool:
    return math.isfinite(msg.range) and msg.min_range <= msg.range <= msg.max_range


def _collect(messages: Iterable[RawMessage], keys: dict[str, str], start_ns: int) -> _Collected:
    out = _Collected()
    for raw in messages:
        topic = keys.get(raw.key)
        t_s = (raw.log_time_ns - start_ns) / 1e9
        try:
            if topic == topics.GROUND_TRUTH_POSE:
                msg = PoseStamped.decode(raw.payload)
                pose = msg.pose.to_pose2d()
                out.truth.append((t_s, msg.header.stamp.to_sec(), pose.x, pose.y, pose.yaw))
            elif topic == topics.POSE2D:
                data = Float64MultiArray.decode(raw.payload).data
                if len(data) >= 3:
                    out.believed.append((t_s, float(data[0]), float(data[1]), float(data[2])))
            elif topic == topics.PLAN:
                path = Path.decode(raw.payload)
                points = np.array([(p.pose.position.x, p.pose.position.y) for p in path.poses]).reshape(-1, 2)
                # an empty path clears the plan (goal reached or canceled): keep the last one that was followed
                if len(points) >= 2 and (not out.plans or not np.array_equal(out.plans[-1], points)):
                    out.plans.append(points)
            elif topic == topics.BATTERY_STATUS:
                out.battery.append((t_s, BatteryState.decode(raw.payload).percentage))
            elif topic == topics.ULTRASONIC:
                sonar = Range.decode(raw.payload)
                if _valid_echo(sonar):
                    out.ranges.append((sonar.header.stamp.to_sec(), sonar.range, sonar.field_of_view))
            elif topic == topics.TF_STATIC and out.mount is None:
                for t in TFMessage.decode(raw.payload).transforms:
                    if t.child_frame_id == topics.ULTRASONIC_FRAME:
                        out.mount = t.transform.to_pose2d()
            elif topic == topics.MAP:
                out.last_map = OccupancyGrid.decode(raw.payload)
        except MessageError:
            continue  # a malformed sample says nothing about the run
    return out


def sonar_echoes(truth: np.ndarray, ranges: np.ndarray, mount: Pose2D) -> np.ndarray:
    """Each echo as the sensor heard it: rows ``(sensor_x, sensor_y, sensor_yaw, range_m, field_of_view_rad)``,
    the sensor's pose from the robot's at the reading's stamp (interpolated) and the mount.

    ``truth`` rows are ``(stamp, x, y, yaw)`` sorted by stamp; ``ranges`` rows ``(stamp, range_m,
    field_of_view_rad)``. Readings outside the poses' time span are left out.
    """
    if len(truth) < 2 or len(ranges) == 0:
        return np.zeros((0, 5))
    inside = (ranges[:, 0] >= truth[0, 0]) & (ranges[:, 0] <= truth[-1, 0])
    ranges = ranges[inside]
    x = np.interp(ranges[:, 0], truth[:, 0], truth[:, 1])
    y = np.interp(ranges[:, 0], truth[:, 0], truth[:, 2])
    yaw = np.interp(ranges[:, 0], truth[:, 0], np.unwrap(truth[:, 3]))
    return np.column_stack(
        [
            x + mount.x * np.cos(yaw) - mount.y * np.sin(yaw),
            y + mount.x * np.sin(yaw) + mount.y * np.cos(yaw),
            yaw + mount.yaw,
            ranges[:, 1],
            ranges[:, 2],
        ]
    )


def _map_image(grid: OccupancyGrid) -> MapImage:
    info = grid.info
    cells = np.asarray(grid.data, dtype=np.int8).reshape(int(info.height), int(info.width))
    return MapImage(cells, info.resolution, info.origin.position.x, info.origin.position.y)


def run_picture(recording: Recording, namespace: str | None = None, world: World | None = None) -> RunPicture:
    """The run in ``recording`` for one robot (``namespace``: default, the recording's own)."""
    ns = recording.recording_info().get("namespace", "") if namespace is None else namespace
    wanted = (
        topics.GROUND_TRUTH_POSE,
        topics.POSE2D,
        topics.PLAN,
        topics.BATTERY_STATUS,
        topics.ULTRASONIC,
        topics.TF_STATIC,
        topics.MAP,
    )
    keys = {topic_key(ns, t): t for t in wanted}
    start_ns, _ = recording.time_range_ns()
    data = _collect(recording.raw_messages([k for k in keys if k in recording.raw_keys()]), keys, start_ns)
    if data.truth:
        truth = np.array(data.truth)
        timed = truth[:, [0, 2, 3]]
        mount = data.mount or Pose2D(0.0, 0.0, 0.0)
        echoes = sonar_echoes(
            truth[np.argsort(truth[:, 1])][:, 1:5], np.array(data.ranges).reshape(-1, 3), mount
        )
    else:
        timed = np.array(data.believed)[:, :3] if data.believed else np.zeros((0, 3))
        echoes = np.zeros((0, 5))
    world = world if world is not None else recording.world()
    return RunPicture(
        world=world,
        map_image=_map_image(data.last_map) if data.last_map is not None and world is None else None,
        planned_paths=data.plans,
        trajectory=timed[:, 1:3],
        trajectory_times_s=timed[:, 0],
        sonar_echoes=echoes,
        battery=np.array(data.battery).reshape(-1, 2),
        title=f"{recording.path.name}" + (f" ({world.name})" if world is not None else ""),
        time_label="time since the recording began [s]",
    )
