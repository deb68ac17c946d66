"""The planner's layered costmap kept current: the static map with remembered glass, lidar and sonar.

Sensor callbacks only hand their newest data over (:meth:`CostmapUpdater.add_scan`,
:meth:`CostmapUpdater.add_range`, :meth:`CostmapUpdater.add_mounts`); :meth:`CostmapUpdater.update`, run
at the node's costmap rate on a worker thread (:mod:`services.planner.costmap_thread`), places each
reading with the robot's pose at its own stamp (:class:`~shared.pose_tracking.PoseTrack`, one snapshot of
it per update, so a scan and an echo are placed through the same map -> odom correction) and the
sensor's mount from ``tf_static``, folds it in and re-inflates, so the control tick finds a cached
snapshot. Sonar echoes the lidar cannot explain are glass: they go into the glass memory
(:mod:`services.planner.glass_memory`), which is folded into the static layer and kept on file. No bus
here: the node wires it.
"""

from __future__ import annotations

import logging
import math
import pathlib
import time
from collections import deque
from typing import Protocol

import numpy as np

from services.planner.costmap import LETHAL_OBSTACLE, CostGrid, LayeredCostmap, laser_scan_points
from services.planner.glass_memory import EXCUSED_RADIUS_SHARE, GlassMemory
from services.planner.glass_store import GlassStore
from services.planner.global_planner import GlobalPlanner
from services.planner.occupancy_map import OCC_OCCUPIED, OccupancyMap
from services.planner.params import Params
from services.planner.range_sensor_model import RangeSensorModel
from services.planner.recovery import GlassClearing
from services.planner.sonar_fusion import echo_explained_by_lidar
from services.planner.suspicion_way import reachable, way_through_suspicion
from shared import topics
from shared.frames import SensorMounts
from shared.geometry import Pose2D, wrap_angle
from shared.messages import Header, LaserScan, Range, TFMessage
from shared.pose_tracking import PoseTrack
from shared.ratelimit import RateLimitedLogger

#: Between costmap updates, sonar readings closer together than this are folded in only once (the newest).
SONAR_MIN_TRAVEL_M = 0.05
SONAR_MIN_TURN_RAD = 0.1
#: A sonar reading newer than the newest odometry waits for it (sim seconds), so that odometry places it;
#: a reading this far from the update's time either way is placed at once, by what the track holds.
SONAR_WAIT_FOR_ODOM_S = 0.5
#: Write the glass memory to its file (when it changed) at most this often (wall seconds).
GLASS_SAVE_PERIOD_S = 1.0
#: A scan this far in time from a sonar reading is too old to explain its echo.
LIDAR_FOR_SONAR_MAX_AGE_S = 0.5
#: A scan placed through a map -> odom correction this far from the echo's cannot explain it either: the
#: localiser moved the robot in between (a teleport, a relocalisation).
LIDAR_FOR_SONAR_MAX_SHIFT_M = 0.05
LIDAR_FOR_SONAR_MAX_TURN_RAD = 0.05
#: The heard glass handed to another thread reaches this much past the slowdown radius round the robot as of
#: the update: at most 0.5 m/s, it drives a tenth of that before the next update, 5-10 per second.
HEARD_GLASS_MARGIN_M = 1.0
#: Glass the sonar heard within this angle of the heading slows the robot (a pane beside it does not).
GLASS_SLOWDOWN_HALF_ANGLE_RAD = math.radians(70.0)


class PoseSource(Protocol):
    """What the updater asks of the pose track (:class:`~shared.pose_tracking.PoseTrack`, or a view of it
    that another thread fills, :class:`~services.planner.costmap_thread.LockedPoseTrack`): a copy to place
    one update's readings with."""

    def snapshot(self) -> PoseTrack: ...


def glass_speed_limit(params: Params, pose: Pose2D | None, heard_xy: np.ndarray) -> float | None:
    """The speed allowed near glass the sonar has heard (Nav2's regulated pure pursuit slows near
    obstacles the same way): the top speed times the distance to the nearest heard cell over
    ``glass_slowdown_radius_m``, at least ``glass_slowdown_min_speed_mps``; None when nothing heard
    is that close. Only glass ahead counts, within ``GLASS_SLOWDOWN_HALF_ANGLE_RAD`` of the heading:
    the limit caps forward speed; a pane beside the robot is passed, not driven into.

    ``heard_xy``: centres ``(N, 2)`` of cells the sonar heard glass in (all of them, or those near ``pose``)."""
    p = params
    if pose is None or p.glass_slowdown_radius_m <= 0 or len(heard_xy) == 0:
        return None
    dx, dy = heard_xy[:, 0] - pose.x, heard_xy[:, 1] - pose.y
    distance = np.hypot(dx, dy)
    along = dx * math.cos(pose.yaw) + dy * math.sin(pose.yaw)
    ahead = (along > math.cos(GLASS_SLOWDOWN_HALF_ANGLE_RAD) * distance) & (
        distance < p.glass_slowdown_radius_m
    )
    if not ahead.any():
        return None
    distance_m = float(np.min(distance[ahead]))
    return max(p.glass_slowdown_min_speed_mps, p.max_linear_vel_mps * distance_m / p.glass_slowdown_radius_m)


def _same_correction(a: Pose2D | None, b: Pose2D | None) -> bool:
    """Whether two readings were placed through (about) the same map -> odom correction (both without
    one counts: they were placed from localisation alone)."""
    if a is None or b is None:
        return a is b
    return (
        a.distance_to(b) <= LIDAR_FOR_SONAR_MAX_SHIFT_M
        and abs(wrap_angle(a.yaw - b.yaw)) <= LIDAR_FOR_SONAR_MAX_TURN_RAD
    )


def _moved(before: Pose2D, after: Pose2D) -> bool:
    """Far enough apart for a sonar reading to say something new."""
    return (
        before.distance_to(after) >= SONAR_MIN_TRAVEL_M
        or abs(wrap_angle(after.yaw - before.yaw)) >= SONAR_MIN_TURN_RAD
    )


class CostmapUpdater:
    """The costmap, the glass memory behind it, and the sensor data waiting to be folded in."""

    def __init__(self, params: Params, tracker: PoseSource, log: logging.Logger) -> None:
        self._params = params
        self._tracker = tracker
        self._log = log
        self._say = RateLimitedLogger(log, interval_s=5.0)
        self.costmap: LayeredCostmap | None = None
        self._base_map: OccupancyMap | None = None
        self.glass: GlassMemory | None = None
        self._glass_store = (
            GlassStore(pathlib.Path(params.glass_memory_file))
            if params.glass_memory_file and params.use_range_layer
            else None
        )
        self._glass_saved_wall_s = 0.0
        self._applied_glass: np.ndarray | None = None
        self._mounts = SensorMounts(
            {
                topics.LIDAR_FRAME: Pose2D(*params.lidar_mount),
                topics.ULTRASONIC_FRAME: Pose2D(*params.ultrasonic_mount),
            }
        )
        #: Sensor data handed over by the callbacks, taken by :meth:`update` (on another thread, see
        #: :mod:`services.planner.costmap_thread`): deques, whose append and popleft need no lock.
        self._pending_scan: deque[LaserScan] = deque(maxlen=1)
        self._pending_mounts: deque[TFMessage] = deque(maxlen=8)
        #: The robot's pose as of the last update (None before one placed it).
        self.last_pose: Pose2D | None = None
        self._pending_ranges: deque[Range] = deque(maxlen=16)
        self._last_range_pose: Pose2D | None = None
        #: The newest scan's hits in the map frame, with its stamp and the map -> odom correction it was
        #: placed through: what the lidar explains of a sonar echo.
        self._lidar_hits: tuple[float, np.ndarray | None] = (-math.inf, None)
        self._lidar_correction: Pose2D | None = None

    # --- inputs -------------------------------------------------------------------------------------

    def set_map(self, occupancy: OccupancyMap) -> None:
        """A new static map: the glass memory follows it (restored from file for a new frame)."""
        self._base_map = occupancy
        if self.glass is None or self.glass.frame != occupancy.frame:
            self.glass = GlassMemory(
                occupancy.frame,
                self._params.costmap_params(),
                self._params.glass_suspicion_radius_m,
                model=RangeSensorModel(trusted_range_m=self._params.glass_trusted_range_m),
                echo_hold_s=self._params.glass_echo_hold_s,
                pane_extension_m=self._params.glass_pane_extension_m,
            )
            kept = self._glass_store.load(occupancy) if self._glass_store is not None else None
            if kept is not None:
                self.glass.restore(kept)
                self._log.info(
                    "glass memory restored from %s (%d cells marked)",
                    self._params.glass_memory_file,
                    int(np.count_nonzero(kept == LETHAL_OBSTACLE)),
                )
        self.glass.set_walls(occupancy.data == OCC_OCCUPIED)
        self._applied_glass = None
        if self.costmap is None:
            self.costmap = LayeredCostmap(occupancy, self._params.costmap_params())
        self.apply_glass()

    def refresh_costmap_params(self) -> None:
        """The parameters' costmap settings changed (``zendock param set``): inflate with them from now on."""
        if self.costmap is not None:
            self.costmap.set_params(self._params.costmap_params())

    def add_scan(self, msg: LaserScan) -> None:
        self._pending_scan.append(msg)

    def add_range(self, msg: Range) -> None:
        self._pending_ranges.append(msg)

    def add_mounts(self, msg: TFMessage) -> None:
        """Sensor mounts (``tf_static``): taken in at the next update, where the readings are placed."""
        self._pending_mounts.append(msg)

    def glass_speed_limit_mps(self, pose: Pose2D | None) -> float | None:
        """:func:`glass_speed_limit` at ``pose``, from the heard cells round it."""
        p = self._params
        if pose is None or self.glass is None or p.glass_slowdown_radius_m <= 0:
            return None
        return glass_speed_limit(
            p, pose, self.glass.heard_cells_xy((pose.x, pose.y), p.glass_slowdown_radius_m)
        )

    def heard_glass_xy(self) -> np.ndarray:
        """Centres ``(N, 2)`` of the cells the sonar heard glass in round the robot as of the last update:
        within :data:`HEARD_GLASS_MARGIN_M` past the slowdown radius, what the next control ticks need
        (the whole grid at every update would be wasted work: measurement 75). None heard, no pose yet, or
        no slowdown: empty."""
        radius = self._params.glass_slowdown_radius_m
        pose = self.last_pose
        if self.glass is None or radius <= 0 or pose is None:
            return np.zeros((0, 2))
        return self.glass.heard_cells_xy((pose.x, pose.y), radius + HEARD_GLASS_MARGIN_M)

    def grid(self) -> CostGrid:
        """The inflated cost grid the planner and the follower read (a snapshot, cached between updates)."""
        assert self.costmap is not None, "no map yet"
        return self.costmap.grid()

    # --- updates ------------------------------------------------------------------------------------

    def update(self, now: float) -> None:
        """Fold the newest scan and the sonar readings since the last update in, clear the footprint."""
        costmap = self.costmap
        if costmap is None:
            return
        while self._pending_mounts:
            self._mounts.update(self._pending_mounts.popleft())
        # Localisation arriving during the update must not place the scan through one correction and the
        # echoes after it through another: an echo heard where the robot was put down was compared with
        # walls the lidar saw from where it had stood, and marked as glass.
        track = self._tracker.snapshot()
        scan = self._pending_scan.popleft() if self._pending_scan else None
        if scan is not None:
            sensor = self._sensor_pose(track, scan.header)
            if sensor is not None:
                stride = self._params.scan_beam_stride
                endpoints, hits = laser_scan_points(
                    sensor.as_tuple(),
                    scan.angle_min,
                    scan.angle_increment * stride,
                    scan.ranges[::stride],
                    scan.range_min,
                    scan.range_max,
                )
                costmap.update_with_scan((sensor.x, sensor.y), endpoints, hits)
                self._lidar_hits = (scan.header.stamp.to_sec(), endpoints[hits])
                self._lidar_correction = track.map_to_odom
        while self._pending_ranges:
            if self._awaits_odometry(track, self._pending_ranges[0], now):
                break  # the next update places it, and the readings after it
            reading = self._pending_ranges.popleft()
            sensor = self._sensor_pose(track, reading.header)
            if sensor is None:
                continue
            last = self._last_range_pose
            if self._pending_ranges and last is not None and not _moved(last, sensor):
                continue  # a reading from (almost) the same place as the last one adds nothing
            if self._fold_in_sonar(sensor, reading, track.map_to_odom, may_wait=bool(self._pending_ranges)):
                self._last_range_pose = sensor
        pose = track.current_pose(now, self._params.pose_timeout_s)
        self.last_pose = pose
        if pose is not None:
            costmap.clear_footprint(pose.as_tuple())
            if self.glass is not None:
                self.glass.observe_footprint(pose.as_tuple())
        if self.glass is not None:
            self.glass.expire(now)
        self.apply_glass()

    def apply_glass(self) -> None:
        """Fold the glass memory into the costmap's static layer, when it changed (and keep it on file)."""
        if self.costmap is None or self._base_map is None or self.glass is None:
            return
        if (
            self._glass_store is not None
            and time.monotonic() - self._glass_saved_wall_s >= GLASS_SAVE_PERIOD_S
        ):
            self._glass_saved_wall_s = time.monotonic()
            try:
                self._glass_store.save_if_changed(self._base_map, self.glass.sonar_layer)
            except OSError as exc:
                self._log.warning("glass memory not saved to %s: %s", self._params.glass_memory_file, exc)
        glass = self.glass.glass_mask()
        if self._applied_glass is not None and np.array_equal(glass, self._applied_glass):
            return
        self._applied_glass = glass
        self.costmap.set_static_map(self._map_with(glass))

    def _map_with(self, glass: np.ndarray) -> OccupancyMap:
        """The static map with ``glass`` (boolean grid) as walls."""
        base = self._base_map
        assert base is not None
        if not glass.any():
            return base
        data = base.data.copy()
        data[glass] = OCC_OCCUPIED
        return OccupancyMap(base.resolution_m, base.origin, data)

    def open_way_through_suspicion(self, start: Pose2D, goal: Pose2D, planner: GlobalPlanner) -> int:
        """If the outer part of suspected glass alone closes every way from ``start`` to ``goal``, excuse the
        suspected cells along a way without it (:mod:`services.planner.suspicion_way`); how many cells."""
        if self.costmap is None or self._base_map is None or self.glass is None:
            return 0
        suspicion = self.glass.suspicion_mask()
        if not suspicion.any() or reachable(planner, self.costmap.grid(), start, goal):
            return 0
        without = self.costmap.grid_over(self._map_with(self.glass.glass_mask(EXCUSED_RADIUS_SHARE)))
        reach_m = self.costmap.params.circumscribed_radius_m + self.costmap.frame.resolution_m
        cells = way_through_suspicion(planner, without, suspicion, start, goal, reach_m)
        if cells is None:
            return 0
        excused = self.glass.excuse_suspicion(cells)
        if excused:
            self.apply_glass()
            self._log.info(
                "suspected glass closed every way to the goal: %d unlooked-at cells on a way through it "
                "are suspected no more (the inner half of the radius still is); the sonar looks there",
                excused,
            )
        return excused

    def clear(self, glass: GlassClearing, robot: Pose2D | None = None) -> None:
        """Forget what the lidar saw (the next scan, all round, refills it) and as much of the glass
        memory as ``glass`` says: none, what lies within ``recovery_glass_clear_radius_m`` of ``robot`` but
        not within its turning reach, or all of it (see :func:`services.planner.recovery.glass_clearing`)."""
        if self.costmap is None:
            return
        self.costmap.clear()
        what = "lidar"
        if glass is not GlassClearing.KEEP and self.glass is not None:
            if glass is GlassClearing.ALL or robot is None:
                self.glass.clear()
                what = "lidar and glass memory"
            else:
                # Glass within the robot's turning reach stays: forgotten there, it is what a stuck robot
                # met next, turning to look round or driving off on the new plan.
                radius, reach = self._params.recovery_glass_clear_radius_m, self.glass.turning_reach_m
                self.glass.clear_around((robot.x, robot.y), radius, keep_within_m=reach)
                what = f"lidar, and glass memory from {reach:.2f} to {radius:g} m"
            self.apply_glass()
        self._log.info("costmap cleared (%s)", what)

    def restore_unheard_glass(self) -> int:
        """After a look round that stopped early: the glass the last clearing forgot where the sonar has
        not looked since comes back (:meth:`GlassMemory.restore_unheard`); how many cells of glass."""
        if self.costmap is None or self.glass is None:
            return 0
        restored = self.glass.restore_unheard()
        self.apply_glass()
        self._log.info("glass memory the look round did not hear again is back: %d cells of glass", restored)
        return restored

    def clear_square(self, centre: tuple[float, float], side_m: float, outside: bool) -> None:
        """Forget what the lidar saw and the glass memory inside the square of side ``side_m`` round
        ``centre`` (or, ``outside``, everywhere else): Nav2's region clears."""
        if self.costmap is None:
            return
        cells = self.costmap.frame.cells_in_square(centre, side_m, outside)
        self.costmap.clear_cells(cells)
        if self.glass is not None:
            self.glass.clear_cells(cells)
            self.apply_glass()
        where = "outside" if outside else "inside"
        self._log.info(
            "costmap cleared %s the %.2f m square round (%.2f, %.2f): lidar and glass memory, %d cells",
            where,
            side_m,
            *centre,
            len(cells),
        )

    def observe_turning_circle(self, pose: Pose2D) -> None:
        """The robot stands still here: let it turn (see :meth:`GlassMemory.observe_turning_circle`)."""
        if self.glass is None:
            return
        self.glass.observe_turning_circle(pose.as_tuple())
        self.apply_glass()

    # --- internals ----------------------------------------------------------------------------------

    @staticmethod
    def _awaits_odometry(track: PoseTrack, reading: Range, now: float) -> bool:
        """Whether a sonar reading is newer than the newest odometry, and should wait for it.

        Placed now, its pose would be the last odometry carried on along its twist, or the last
        localisation sample held: a robot starting to turn is not where either puts it. A reading taken
        facing just past a pane's end (no echo) was placed 5 degrees back, facing the pane, and cleared the
        floor behind the glass to 3 m; the planner then routed the robot's corner into the pane's end.
        Without odometry, or for a reading far from ``now`` (a clock that went back), nothing waits."""
        latest = track.latest_odom
        stamp_s = reading.header.stamp.to_sec()
        return latest is not None and latest.stamp_s < stamp_s and abs(now - stamp_s) < SONAR_WAIT_FOR_ODOM_S

    def _sensor_pose(self, track: PoseTrack, header: Header) -> Pose2D | None:
        robot = track.pose_now_at(header.stamp.to_sec())
        mount = self._mounts.get(header.frame_id)
        if robot is None or mount is None:
            if mount is None:
                self._say.warning(
                    f"frame:{header.frame_id}", "no mount known for sensor frame %r", header.frame_id
                )
            return None
        return robot.compose(mount)

    def _fold_in_sonar(
        self, sensor: Pose2D, reading: Range, correction: Pose2D | None, may_wait: bool
    ) -> bool:
        """Into glass memory: an echo the lidar cannot explain marks; one it explains only clears.

        Only a scan from about the same time can tell glass from a wall. With ``may_wait`` (a later
        reading is queued) an echo with no such scan is left out (False) for that later one: between idle
        updates, 1 s apart, the first echo after a teleport was compared with no scan from the new place
        and marked the wall it heard as glass. The last reading is judged even so: a dead lidar still
        leaves the sonar's marks.
        """
        glass = self.glass
        if glass is None:
            return True
        echo = reading.min_range <= reading.range < reading.max_range
        hits_stamp_s, hits = self._lidar_hits
        fresh = abs(
            reading.header.stamp.to_sec() - hits_stamp_s
        ) <= LIDAR_FOR_SONAR_MAX_AGE_S and _same_correction(self._lidar_correction, correction)
        if echo and not fresh and may_wait:
            return False
        if (
            echo
            and fresh
            and echo_explained_by_lidar(sensor.as_tuple(), reading.range, reading.field_of_view, hits)
        ):
            glass.add_clear_view(
                sensor.as_tuple(),
                reading.range - glass.frame.resolution_m,
                reading.field_of_view,
                reading.min_range,
            )
            return True
        glass.add_reading(
            sensor.as_tuple(),
            reading.range,
            reading.field_of_view,
            reading.min_range,
            reading.max_range,
            stamp_s=reading.header.stamp.to_sec(),
        )
        return True
