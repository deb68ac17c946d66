"""A run as a picture: the room, the plan, the path driven, what the sonar heard, and the battery over time.

Takes plain data (:func:`plot_run` with lists, or a :class:`RunPicture`), so anything that has a run's
numbers can draw it: ``zendock plot`` reads them from a recording, ``zendock demo`` from its own run. Drawn
with matplotlib's Agg backend (no display needed). Walls are black, glass light blue, docks green with
their staging pose in orange, the plans dashed (the last full plan bold), the driven trajectory coloured by
time, each sonar echo a thin light arc at its range across the cone (the sonar hears the nearest surface
anywhere in its cone, so a dot on the beam's axis would claim more than it knows).

The picture says what happened, not what was assumed: the battery panel starts at the first reading
the run had (after a ``battery/set_state``, at the set), and marks events such as the set and the
docking trigger on the same time axis the trajectory is coloured by.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.patches import Polygon

from shared.foxglove_view.scene import DEFAULT_STAGING_OFFSET_M, staging_pose
from shared.models.footprint import footprint_corners
from shared.world import DOCK_GEOMETRY, ROBOT_LENGTH_M, ROBOT_WIDTH_M, World

WALL_COLOR = "black"
GLASS_COLOR = "#7ec8f0"
BOX_COLOR = "#9c8c7a"
DOCK_COLOR = "#1a9e3a"
STAGING_COLOR = "#ff9900"
PLAN_COLOR = "#d62728"
SONAR_COLOR = "#e41a1c"
GLASS_MEMORY_COLOR = "#1f5fa8"
FALSE_GLASS_COLOR = "#ff00c8"
RECOVERY_COLOR = "#8a2be2"
BATTERY_COLOR = "#1f77b4"
TRAJECTORY_CMAP = "viridis"
EVENT_COLOR = "#555555"

#: Plans whose last points are this close go to the same goal (the planner replans to it as the robot drives).
SAME_GOAL_M = 0.10
#: A plan at least this fraction of the longest plan to its goal still covers the whole way: a "full" plan.
#: Replans made on the way cover only what is left (down to a stub a few centimetres from the goal).
FULL_PLAN_FRACTION = 0.9
#: A battery reading within this of the value set by ``battery/set_state`` is the set's own reading.
BATTERY_SET_TOLERANCE = 0.02
#: Points along one echo's arc: enough for a smooth curve at the picture's scale.
ECHO_ARC_POINTS = 9


@dataclass(frozen=True)
class MapImage:
    """An occupancy grid to draw under the run when there is no world file (cells -1, 0..100)."""

    cells: np.ndarray  # (height, width) int8, row 0 at the origin's y
    resolution_m: float
    origin_x_m: float
    origin_y_m: float


@dataclass
class RunPicture:
    """What a run picture shows; every part is optional.

    ``trajectory``: ``(N, 2)`` driven positions, with ``trajectory_times_s`` (``N``, on the clock
    ``time_label`` names) to colour them by time (else by progress along the track, labelled so);
    ``planned_paths``: each ``(K, 2)`` in the map frame, in the order planned: every plan is drawn faintly,
    the last full plan (:func:`last_full_plan`) bold; ``sonar_echoes``: rows ``(sensor_x, sensor_y,
    sensor_yaw, range_m, field_of_view_rad)``, the sensor's pose in the map when the reading was taken,
    each drawn as the arc at its range across the cone; ``collisions``: ``(C, 2)`` where the robot touched
    something; ``recoveries``: ``(R, 2)`` where navigation began a recovery; ``glass_marks`` and
    ``false_glass_marks``: the planner's glass memory at the end, the marks near a real pane and those
    more than 10 cm from every pane; ``battery``: rows ``(t_s, percentage 0..1)``, on the same clock as
    the trajectory's times; ``events``: ``(t_s, label)`` marked on the battery panel.
    """

    world: World | None = None
    map_image: MapImage | None = None
    planned_paths: list[np.ndarray] = field(default_factory=list)
    trajectory: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    trajectory_times_s: np.ndarray | None = None
    sonar_echoes: np.ndarray = field(default_factory=lambda: np.zeros((0, 5)))
    collisions: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    recoveries: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    glass_marks: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    false_glass_marks: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    battery: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    events: list[tuple[float, str]] = field(default_factory=list)
    title: str = ""
    staging_offset_m: float = DEFAULT_STAGING_OFFSET_M
    time_label: str = "sim time [s]"

    @property
    def sonar_hits(self) -> np.ndarray:
        """``(M, 2)``: each echo's point on the beam's axis (for counting; the echo is anywhere on its arc)."""
        e = self.sonar_echoes
        return np.column_stack([e[:, 0] + e[:, 3] * np.cos(e[:, 2]), e[:, 1] + e[:, 3] * np.sin(e[:, 2])])


def plan_length_m(path: np.ndarray) -> float:
    """The length of a polyline ``(K, 2)``."""
    return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum()) if len(path) >= 2 else 0.0


def last_full_plan(plans: Sequence[np.ndarray], full_fraction: float = FULL_PLAN_FRACTION) -> int | None:
    """The index of the plan to draw bold: the route to the last goal, not the remainder the planner sends
    as the robot closes in (which ends as a stub of a few centimetres). Among the last run of plans to the
    same goal (end points within :data:`SAME_GOAL_M`), the last one at least ``full_fraction`` of the
    longest: the route as planned when the robot set off, or as replanned early on (a detour).
    ``None`` when there is no drawable plan."""
    drawable = [i for i, p in enumerate(plans) if len(p) >= 2]
    if not drawable:
        return None
    goal = plans[drawable[-1]][-1]
    same_goal: list[int] = []
    for i in reversed(drawable):
        if math.dist(plans[i][-1], goal) > SAME_GOAL_M:
            break
        same_goal.insert(0, i)
    longest_m = max(plan_length_m(plans[i]) for i in same_goal)
    return [i for i in same_goal if plan_length_m(plans[i]) >= full_fraction * longest_m][-1]


def echo_arc(
    sensor_x: float,
    sensor_y: float,
    sensor_yaw: float,
    range_m: float,
    field_of_view_rad: float,
    points: int = ECHO_ARC_POINTS,
) -> np.ndarray:
    """``(points, 2)``: where an echo at ``range_m`` may have come from, the arc of that radius about the
    sensor across its cone (``field_of_view_rad`` wide, centred on ``sensor_yaw``)."""
    bearings = sensor_yaw + np.linspace(-0.5, 0.5, points) * field_of_view_rad
    return np.column_stack([sensor_x + range_m * np.cos(bearings), sensor_y + range_m * np.sin(bearings)])


def battery_from_set(
    battery: np.ndarray, set_s: float, set_percentage: float, tolerance: float = BATTERY_SET_TOLERANCE
) -> np.ndarray:
    """The battery series the run had once ``battery/set_state`` took effect: from the first reading at or
    after ``set_s`` within ``tolerance`` of ``set_percentage`` (readings published while the request
    was on its way still carry the old charge); from ``set_s`` when no reading shows the set."""
    later = battery[battery[:, 0] >= set_s] if len(battery) else battery
    shows_set: np.ndarray = (
        np.flatnonzero(np.abs(later[:, 1] - set_percentage) <= tolerance)
        if len(later)
        else np.zeros(0, dtype=int)
    )
    return later[shows_set[0] :] if len(shows_set) else later


def _points(values: Sequence[Sequence[float]] | np.ndarray, columns: int) -> np.ndarray:
    return np.asarray(values, dtype=np.float64).reshape(-1, columns)


def draw_world(ax: plt.Axes, world: World, staging_offset_m: float) -> None:
    for i, ((x1, y1), (x2, y2)) in enumerate(world.boundary_walls() + list(world.walls)):
        ax.plot(
            [x1, x2],
            [y1, y2],
            color=WALL_COLOR,
            linewidth=3,
            solid_capstyle="round",
            label="walls" if i == 0 else None,
            zorder=3,
        )
    for i, ((x1, y1), (x2, y2)) in enumerate(world.glass):
        ax.plot(
            [x1, x2],
            [y1, y2],
            color=GLASS_COLOR,
            linewidth=5,
            solid_capstyle="round",
            label="glass" if i == 0 else None,
            zorder=3,
        )
    for i, box in enumerate(world.boxes):
        ax.add_patch(
            Polygon(
                box.corners(),
                closed=True,
                facecolor=BOX_COLOR,
                edgecolor=WALL_COLOR,
                label="box (an obstacle)" if i == 0 else None,
                zorder=3,
            )
        )
    for i, dock in enumerate(world.docks):
        body = DOCK_GEOMETRY.body_box(dock)
        ax.add_patch(
            Polygon(
                body.corners(),
                closed=True,
                facecolor=DOCK_COLOR,
                edgecolor="none",
                label="dock (arrow: the way a docked robot faces)" if i == 0 else None,
                zorder=3,
            )
        )
        pose = dock.pose2d
        # The dock's pose is where the robot's centre is when docked: its outline there shows the gap
        # between the end of the track and the dock's body as intended.
        ax.add_patch(
            Polygon(
                footprint_corners(pose, ROBOT_LENGTH_M, ROBOT_WIDTH_M),
                closed=True,
                facecolor="none",
                edgecolor=DOCK_COLOR,
                linestyle="--",
                linewidth=1,
                label="robot docked (centre at the dock's pose)" if i == 0 else None,
                zorder=4,
            )
        )
        ax.annotate(
            "",
            xy=(pose.x + 0.25 * np.cos(pose.yaw), pose.y + 0.25 * np.sin(pose.yaw)),
            xytext=(pose.x, pose.y),
            arrowprops={"arrowstyle": "->", "color": DOCK_COLOR, "lw": 2},
            zorder=4,
        )
        staging = staging_pose(pose, staging_offset_m)
        ax.plot(
            [staging.x],
            [staging.y],
            marker="D",
            color=STAGING_COLOR,
            markersize=7,
            linestyle="none",
            label="staging pose" if i == 0 else None,
            zorder=5,
        )


def _draw_map(ax: plt.Axes, image: MapImage) -> None:
    cells = image.cells.astype(np.float64)
    shade = np.where(cells < 0, 0.85, 1.0 - np.clip(cells, 0, 100) / 100.0)
    height, width = cells.shape
    extent = (
        image.origin_x_m,
        image.origin_x_m + width * image.resolution_m,
        image.origin_y_m,
        image.origin_y_m + height * image.resolution_m,
    )
    ax.imshow(shade, cmap="gray", vmin=0.0, vmax=1.0, origin="lower", extent=extent, zorder=0)


def _draw_run(ax: plt.Axes, fig: plt.Figure, picture: RunPicture) -> None:
    bold = last_full_plan(picture.planned_paths)
    faint_label: str | None = "other plans (each from where the robot stood)"
    for i, path in enumerate(picture.planned_paths):
        if i != bold and len(path) >= 2:
            ax.plot(
                path[:, 0],
                path[:, 1],
                color=PLAN_COLOR,
                linestyle="--",
                linewidth=1,
                alpha=0.3,
                zorder=6,
                label=faint_label,
            )
            faint_label = None
    if bold is not None:
        full = picture.planned_paths[bold]
        label = (
            f"last plan from start to goal ({bold + 1} of {len(picture.planned_paths)} plans)"
            if len(picture.planned_paths) > 1
            else "planned path"
        )
        ax.plot(full[:, 0], full[:, 1], color=PLAN_COLOR, linestyle="--", linewidth=2, label=label, zorder=7)
    for marks, colour, label in (
        (picture.glass_marks, GLASS_MEMORY_COLOR, "glass memory"),
        (picture.false_glass_marks, FALSE_GLASS_COLOR, "false glass"),
    ):
        if len(marks):
            ax.scatter(
                marks[:, 0], marks[:, 1], s=9, marker="s", color=colour, alpha=0.7, label=label, zorder=5
            )
    if len(picture.collisions):
        ax.scatter(
            picture.collisions[:, 0],
            picture.collisions[:, 1],
            s=90,
            marker="X",
            color="black",
            label="collision",
            zorder=10,
        )
    if len(picture.recoveries):
        ax.scatter(
            picture.recoveries[:, 0],
            picture.recoveries[:, 1],
            s=110,
            marker="o",
            facecolors="none",
            edgecolors=RECOVERY_COLOR,
            linewidths=2,
            label="recovery",
            zorder=10,
        )
    echoes = picture.sonar_echoes
    if len(echoes):
        ax.add_collection(
            LineCollection(
                [echo_arc(*row) for row in echoes], colors=SONAR_COLOR, linewidths=0.5, alpha=0.15, zorder=6
            )
        )
        ax.plot(
            [],
            [],
            color=SONAR_COLOR,
            linewidth=1,
            alpha=0.6,  # the legend's sample, visible
            label="sonar echoes (arc at range across the cone)",
        )
    traj = picture.trajectory
    if len(traj) >= 2:
        timed = picture.trajectory_times_s is not None and len(picture.trajectory_times_s) == len(traj)
        colour_by = np.asarray(picture.trajectory_times_s) if timed else np.linspace(0.0, 100.0, len(traj))
        points = traj.reshape(-1, 1, 2)
        segments = np.concatenate([points[:-1], points[1:]], axis=1)
        lines = LineCollection(list(segments), cmap=TRAJECTORY_CMAP, linewidth=2.5, zorder=8)
        lines.set_array(colour_by[:-1])
        ax.add_collection(lines)
        fig.colorbar(
            lines,
            ax=ax,
            fraction=0.035,
            pad=0.02,
            label=picture.time_label if timed else "progress along the track [%] (no times)",
        )
        ax.plot(
            [traj[0, 0]],
            [traj[0, 1]],
            marker="o",
            color="black",
            markersize=6,
            linestyle="none",
            label="start",
            zorder=9,
        )
        ax.plot(
            [traj[-1, 0]],
            [traj[-1, 1]],
            marker="s",
            color="black",
            markersize=6,
            linestyle="none",
            label="end (robot's centre)",
            zorder=9,
        )


def _frame(ax: plt.Axes, picture: RunPicture) -> None:
    """Fit the room (or whatever was drawn) with a small margin."""
    if picture.world is not None:
        xmin, ymin, xmax, ymax = picture.world.bounds
        ax.set_xlim(xmin - 0.2, xmax + 0.2)
        ax.set_ylim(ymin - 0.2, ymax + 0.2)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, linewidth=0.3, alpha=0.5)


def _draw_battery(
    ax: plt.Axes, battery: np.ndarray, events: Sequence[tuple[float, str]], time_label: str
) -> None:
    ax.set_title("battery")
    ax.set_xlabel(time_label)
    ax.set_ylabel("charge [%]")
    ax.set_ylim(0, 105)
    ax.grid(True, linewidth=0.3, alpha=0.5)
    if len(battery) == 0:
        ax.text(0.5, 0.5, "no battery_status recorded", ha="center", va="center", transform=ax.transAxes)
        return
    ax.plot(battery[:, 0], battery[:, 1] * 100.0, color=BATTERY_COLOR, linewidth=2)
    ax.fill_between(battery[:, 0], 0, battery[:, 1] * 100.0, color=BATTERY_COLOR, alpha=0.15)
    t_min, t_max = float(battery[0, 0]), float(battery[-1, 0])
    for k, (t_s, label) in enumerate(events):
        ax.axvline(t_s, color=EVENT_COLOR, linestyle=":", linewidth=1.2)
        late = t_max > t_min and (t_s - t_min) / (t_max - t_min) > 0.7  # written leftwards, inside the panel
        ax.text(
            t_s,
            102 - 7 * k,
            f"{label} " if late else f" {label}",
            color=EVENT_COLOR,
            fontsize=8,
            va="top",
            ha="right" if late else "left",
        )


def plot_picture(picture: RunPicture, output: str | Path, dpi: int = 120) -> Path:
    """Draw ``picture`` into a PNG at ``output``; returns the path written."""
    fig, (room, battery) = plt.subplots(1, 2, figsize=(13, 6), gridspec_kw={"width_ratios": [2.2, 1]})
    try:
        if picture.map_image is not None and picture.world is None:
            _draw_map(room, picture.map_image)
        if picture.world is not None:
            draw_world(room, picture.world, picture.staging_offset_m)
        _draw_run(room, fig, picture)
        _frame(room, picture)
        room.set_title(picture.title or (picture.world.name if picture.world is not None else "run"))
        handles, labels = room.get_legend_handles_labels()
        _draw_battery(battery, picture.battery, picture.events, picture.time_label)
        if handles:
            # Across the figure's foot, three columns: every label whole, the room keeps its size.
            fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
            rows = -(-len(handles) // 3)
            fig.tight_layout(rect=(0.0, min(0.4, 0.035 * rows + 0.02), 1.0, 1.0))
        else:
            fig.tight_layout()
        path = Path(output)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)
    return path


def plot_run(
    world: World | None,
    output: str | Path,
    *,
    driven: Sequence[Sequence[float]] | np.ndarray = (),
    driven_times_s: Sequence[float] | np.ndarray | None = None,
    plans: Sequence[Sequence[Sequence[float]] | np.ndarray] = (),
    sonar_echoes: Sequence[Sequence[float]] | np.ndarray = (),
    battery: Sequence[Sequence[float]] | np.ndarray = (),
    battery_set: tuple[float, float] | None = None,
    events: Sequence[tuple[float, str]] = (),
    collisions: Sequence[Sequence[float]] | np.ndarray = (),
    recoveries: Sequence[Sequence[float]] | np.ndarray = (),
    glass_marks: Sequence[Sequence[float]] | np.ndarray = (),
    false_glass_marks: Sequence[Sequence[float]] | np.ndarray = (),
    title: str = "",
    map_image: MapImage | None = None,
    dpi: int = 120,
) -> Path:
    """Draw a run from plain lists: ``driven`` ``(x, y)`` points (``driven_times_s``, sim seconds, to colour
    them by time), ``plans`` as lists of ``(x, y)`` in planning order (the last full one bold),
    ``sonar_echoes`` ``(sensor_x, sensor_y, sensor_yaw, range_m, field_of_view_rad)``, ``collisions``,
    ``recoveries``, ``glass_marks`` and ``false_glass_marks`` ``(x, y)``, ``battery`` ``(t_s, percentage
    0..1)``; ``battery_set`` ``(t_s, percentage)`` when the run set the charge (the battery is drawn from
    the set on, and the set marked), ``events`` ``(t_s, label)`` to mark. Returns the PNG's path.
    """
    charge = _points(battery, 2)
    marks = list(events)
    if battery_set is not None:
        charge = battery_from_set(charge, *battery_set)
        marks.insert(
            0, (float(charge[0, 0]) if len(charge) else battery_set[0], f"set to {battery_set[1]:.0%}")
        )
    picture = RunPicture(
        world=world,
        map_image=map_image,
        planned_paths=[_points(p, 2) for p in plans],
        trajectory=_points(driven, 2),
        trajectory_times_s=None if driven_times_s is None else np.asarray(driven_times_s, dtype=np.float64),
        sonar_echoes=_points(sonar_echoes, 5),
        collisions=_points(collisions, 2),
        recoveries=_points(recoveries, 2),
        glass_marks=_points(glass_marks, 2),
        false_glass_marks=_points(false_glass_marks, 2),
        battery=charge,
        events=marks,
        title=title,
    )
    return plot_picture(picture, output, dpi)


class TrialOutcome(Protocol):
    """What the histograms read of a trial (``deploy.trials.TrialResult`` has it)."""

    docked: bool
    dock_time_s: float
    lateral_error_m: float
    yaw_error_rad: float


def _histogram_range(values: Sequence[float]) -> tuple[float, float] | None:
    """None (the data's own range) unless the values are all but equal: the simulation is deterministic, two
    trials can dock in 6.9 s and 6.900000000000002 s, and numpy cannot split such a range into bins."""
    low, high = min(values), max(values)
    scale = max(abs(low), abs(high), 1.0)
    if high - low > 1e-9 * scale:
        return None
    pad = 0.05 * scale
    return (low - pad, high + pad)


def plot_trial_histograms(results: Sequence[TrialOutcome], path: Path) -> None:
    """Dock time, lateral and yaw error of the docked trials, one panel each."""
    ok = [r for r in results if r.docked]
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    panels = [
        ("dock time (s, sim)", [r.dock_time_s for r in ok], "#4472c4"),
        ("lateral error at contact (mm)", [1000 * r.lateral_error_m for r in ok], "#ed7d31"),
        ("yaw error at contact (deg)", [math.degrees(r.yaw_error_rad) for r in ok], "#70ad47"),
    ]
    for ax, (title, values, colour) in zip(axes, panels):
        if values:
            ax.hist(
                values,
                bins=min(30, max(5, len(values) // 3)),
                range=_histogram_range(values),
                color=colour,
                edgecolor="white",
            )
        ax.set_title(title)
        ax.set_ylabel("trials")
    fig.suptitle(f"{len(ok)}/{len(results)} docked")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
