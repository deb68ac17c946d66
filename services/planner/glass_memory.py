"""Glass: what the sonar alone has found, and where a pane it has only partly seen may go on unseen.

The robot's one sonar looks forward through a 0.5 rad cone, so a pane is seen only where the robot
happened to face it. Driving round the end of a partly seen pane, the part never faced (the last
0.3 m in the glass room) is open floor on every layer, and the path cuts close to it. Glass memory
keeps the sonar's own evidence (echoes the lidar cannot explain, see
:mod:`services.planner.sonar_fusion`, and the cones it looked through, weighed by the probabilistic
model of :mod:`services.planner.range_sensor_model` and accumulated as log-odds) and treats a cell as
glass when the sonar marked it, or when the sonar has never looked at it and it lies within
``suspicion_radius_m`` of a cell the sonar heard glass in (marked, or with evidence too weak to mark): a
pane probably goes on, and the robot may pass there only once its sonar has looked. Cells the robot's
footprint has covered are known to be free.

Where on its arc an echo came from is told by the echoes before it (:mod:`services.planner.echo_pairing`):
an earlier echo of the same surface, heard from elsewhere, agrees with it only where one straight surface
would touch both arcs or cross both cones' edges, so the occupied evidence goes there, and not to the rest
of the arc, which lies on open floor in front of an oblique pane or beside a pane's end (what that did to
the false glass of generated rooms is measurement 102). An echo no earlier one can place gives its arc
``unplaced_echo_share`` of its evidence (a near one still marks) and waits; the first later echo that can
place it gives it the rest where the two agree.

The evidence model weighs an echo less toward the cone's edge, because an echo says only that the
nearest surface lies somewhere on the arc; that keeps false glass out of the memory, but a pane's end
heard only at the cone's edge is not marked by one echo, and the robot may drive on and clip it with a
front corner (the cone does not cover the corners until 0.6 m ahead). So each unexplained echo's whole
arc is also held as glass for ``echo_hold_s`` (Nav2 pairs its range layer with a collision monitor for
the same reason): long enough to steer round what was just heard, too short to pile up false glass. The
held arcs never enter the memory kept on file and never count in the yardstick; only the evidence does.

A pane goes on in its own direction, too: a run of marks along a straight line, long enough to be a pane,
is carried on along that line past both ends, through floor the sonar has never looked at, for
``pane_extension_m`` (:mod:`services.planner.pane_extension`). Rounding the far end of a pane heard only
from afar, the last marks can lie short of the end by more than the suspicion radius, and the robot's corner
clipped the end (measurement 81). No extension comes back into floor a recovery has just cleared round the
robot.

Suspicion follows a heard pane's line as well (:meth:`GlassMemory.heard_line_mask`). A pane heard only from
afar and at a slant is often never marked: its far echoes give too little evidence, and the evidence lands a
few centimetres off the pane (the nearest echo comes from the cone's edge, the evidence goes mostly to its
middle). Suspicion round such heard cells stopped short of the pane's end, and even with every reading placed
by its own odometry the robot rounded the end with too little to spare (measurement 92). So a run of heard
cells along a line is carried on along it for up to ``HEARD_LINE_EXTENSION_M``, and unlooked-at floor within
the suspicion radius of that line is suspected too. Such a pane is heard in patches, so heard cells up to
``HEARD_LINE_MAX_GAP_M`` apart along the line make one run, carried on past the last patch (measurement
115). The line itself may cross floor the sonar has looked at (it runs a few centimetres off the pane); only
the floor nobody looked at is suspected.

The node folds the glass into the costmap's static layer (it is as good as a wall until cleared), so
the lidar's clearing never erases it; a recovery or a clear request forgets it.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from services.planner.costmap import FREE_SPACE, LETHAL_OBSTACLE, NO_INFORMATION, CostmapParams
from services.planner.distance_transform import squared_distance_to_marks
from services.planner.echo_pairing import Echo, EchoPairing, placed_by
from services.planner.grid_frame import GridFrame
from services.planner.pane_extension import MAX_GAP_CELLS, pane_extensions
from services.planner.range_sensor_model import RangeSensorModel, reading_evidence

#: Evidence above this (log-odds; P = 0.55) and below the mark threshold is suspected glass.
SUSPECTED_LOG_ODDS = 0.2
#: An echo no other echo has placed yet (see :mod:`services.planner.echo_pairing`) gives its arc only part of
#: its evidence, but never less than this where it gave any: enough to count as heard.
HEARD_FLOOR_LOG_ODDS = SUSPECTED_LOG_ODDS + 0.01
#: Where suspicion alone closed every way and was excused (:meth:`GlassMemory.excuse_suspicion`), the floor
#: this share of the suspicion radius from heard glass is still suspected: a heard pane's end keeps a
#: margin the robot's corners do not cross.
EXCUSED_RADIUS_SHARE = 0.5
#: How far the sensor's pose (and so any cell as the sonar sees it) may be off: a reading clears only
#: cells that lie whole inside its cone by this margin.
SENSOR_POSE_MARGIN_M = 0.01
#: A run of heard cells along a line seeds suspicion this far past its ends (at most the pane extension):
#: enough to reach a pane's end from the last cell heard from afar (measurement 92).
HEARD_LINE_EXTENSION_M = 0.8
#: Heard cells along a line this far apart still make one run. A pane heard only at a slant is heard in
#: patches (an echo is placed where it and an earlier one agree, see :mod:`services.planner.echo_pairing`):
#: cut at the marks' gap of a few cells, the last patches made no run long enough to be a pane and the line
#: stopped short of the pane's end (measurement 115).
HEARD_LINE_MAX_GAP_M = 0.6
#: The heard lines are drawn again only when this many heard cells (or this share of them) changed since
#: they were last drawn: each echo changes a few, and finding the lines through a large hall's heard cells
#: is too dear for every costmap update (measurement 92).
HEARD_LINE_REUSE_CELLS = 8
HEARD_LINE_REUSE_SHARE = 0.03
#: ... or when one newly heard cell lies this close (cells) to where a heard line goes on: it lengthens the
#: run, and the line must start again from the run's new end. A robot driving along a pane hears its end a
#: few cells at a time; counted against the threshold alone, a metre of new cells went unseen and the line
#: went on from where the run had ended long before (the glass room's pane end, measurement 117).
HEARD_LINE_NEAR_CELLS = 3.0


class GlassMemory:
    """The sonar's evidence on one grid, and the glass it implies."""

    def __init__(
        self,
        frame: GridFrame,
        params: CostmapParams,
        suspicion_radius_m: float = 0.5,
        model: RangeSensorModel | None = None,
        echo_hold_s: float = 0.0,
        pane_extension_m: float = 0.0,
    ) -> None:
        if not (math.isfinite(suspicion_radius_m) and suspicion_radius_m >= 0):
            raise ValueError(f"suspicion_radius_m must be a non-negative number, got {suspicion_radius_m}")
        if not (math.isfinite(pane_extension_m) and pane_extension_m >= 0):
            raise ValueError(f"pane_extension_m must be a non-negative number, got {pane_extension_m}")
        self.pane_extension_m = pane_extension_m
        #: Squared distance (cells) to the static map's walls, exact out to the farthest a line stops short
        #: of them (see :meth:`set_walls`); None until the walls are known.
        self._wall_squared: np.ndarray | None = None
        #: Cells a recovery cleared (:meth:`clear_around`): no pane's extension comes back into them. It
        #: would refill at once the floor the recovery had just forgotten to let the robot out, and the
        #: robot would be blocked again, recovery after recovery.
        self._cleared_by_recovery = np.zeros(frame.shape, dtype=bool)
        #: Cells whose heard glass a clearing forgot (:meth:`clear`, :meth:`clear_cells`,
        #: :meth:`clear_around`); the robot still slows near those the sonar has not looked at since
        #: (:meth:`heard_cells_xy`). Forgotten and planned through, a pane's far end was met at 0.35 m/s.
        self._forgotten_glass = np.zeros(frame.shape, dtype=bool)
        #: What the last :meth:`clear_around` forgot, as it was: the cells ``(N, 2)``, then their log-odds,
        #: looked-at, excused and cleared-by-recovery values (see :meth:`restore_unheard`).
        self._forgotten: tuple[np.ndarray, ...] | None = None
        #: The last extension and the marks it was drawn from (most updates change no mark).
        self._extension_cache: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        #: The last heard line's extension and the heard cells it was drawn from.
        self._heard_line_cache: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        if not (math.isfinite(echo_hold_s) and echo_hold_s >= 0):
            raise ValueError(f"echo_hold_s must be a non-negative number, got {echo_hold_s}")
        self.echo_hold_s = echo_hold_s
        #: Recent unexplained echoes' arcs: (time they lapse, cells (N, 2)), oldest first.
        self._held: deque[tuple[float, np.ndarray]] = deque()
        #: The cells under the robot at its last observed pose (a held arc never covers the robot).
        self._under_robot = np.zeros((0, 2), dtype=np.int64)
        self.frame = frame
        self.params = params
        self.suspicion_radius_m = suspicion_radius_m
        self.model = model or RangeSensorModel()
        #: Log-odds that a cell is occupied by glass (0: no evidence either way).
        self._log_odds = np.zeros(frame.shape, dtype=np.float32)
        #: Whether the sonar (or the robot's footprint) has ever covered a cell.
        self._seen = np.zeros(frame.shape, dtype=bool)
        #: The latest unexplained echoes, to tell where on its arc each new one came from.
        self._pairing = EchoPairing()
        #: Suspected cells the planner let the robot pass because suspicion alone closed every way to its
        #: goal (:meth:`excuse_suspicion`): suspected only within :data:`EXCUSED_RADIUS_SHARE` of the radius.
        self._excused = np.zeros(frame.shape, dtype=bool)

    @property
    def sonar_layer(self) -> np.ndarray:
        """Per cell: 254 glass (evidence above the mark threshold), 0 looked at, 255 never looked at."""
        layer = np.full(self.frame.shape, NO_INFORMATION, dtype=np.uint8)
        layer[self._seen] = FREE_SPACE
        layer[self._log_odds >= self.model.mark_log_odds] = LETHAL_OBSTACLE
        return layer

    def add_reading(
        self,
        sensor_pose: tuple[float, float, float],
        range_m: float,
        field_of_view_rad: float,
        min_range_m: float,
        max_range_m: float,
        stamp_s: float | None = None,
    ) -> None:
        """An echo the lidar cannot explain (or no echo): evidence of glass at its range, of free space
        short of it, and (given the reading's ``stamp_s``) its whole arc held as glass for
        ``echo_hold_s``. NaN, -inf and readings under ``min_range`` are ignored."""
        if math.isnan(range_m) or range_m < min_range_m or not (field_of_view_rad > 0):
            return
        echo = range_m < max_range_m
        if not echo and not self.params.range_clear_on_max_reading:
            return
        self._apply(sensor_pose, range_m if echo else max_range_m, field_of_view_rad, echo)
        if echo and stamp_s is not None and self.echo_hold_s > 0:
            self._held.append(
                (stamp_s + self.echo_hold_s, self._arc_cells(sensor_pose, range_m, field_of_view_rad))
            )

    def _arc_cells(
        self, sensor_pose: tuple[float, float, float], range_m: float, fov_rad: float
    ) -> np.ndarray:
        """On-grid cells ``(N, 2)`` the arc across the cone at ``range_m`` passes through."""
        sx, sy, syaw = sensor_pose
        count = max(2, math.ceil(fov_rad * range_m / (0.5 * self.frame.resolution_m)) + 1)
        angles = syaw + np.linspace(-0.5 * fov_rad, 0.5 * fov_rad, count)
        points = np.stack([sx + range_m * np.cos(angles), sy + range_m * np.sin(angles)], axis=1)
        cells = self.frame.world_to_cells(points)
        return np.unique(cells[self.frame.cells_in_bounds(cells)], axis=0)

    def expire(self, now_s: float) -> bool:
        """Let held arcs lapse at ``now_s`` (sim time); whether any did. A clock that went back (a new
        run in the same process) lets them all lapse."""
        held = self._held
        lapsed = False
        while held and (held[0][0] <= now_s or held[0][0] - self.echo_hold_s > now_s + 1.0):
            held.popleft()
            lapsed = True
        return lapsed

    def held_mask(self) -> np.ndarray:
        """Boolean ``(height, width)``: the held arcs, less the cells under the robot."""
        mask = np.zeros(self.frame.shape, dtype=bool)
        for _, cells in self._held:
            mask[cells[:, 1], cells[:, 0]] = True
        under = self._under_robot
        mask[under[:, 1], under[:, 0]] = False
        return mask

    def add_clear_view(
        self,
        sensor_pose: tuple[float, float, float],
        clear_to_m: float,
        field_of_view_rad: float,
        min_range_m: float,
    ) -> None:
        """The sonar saw nothing but what the lidar sees: nothing in the cone before ``clear_to_m``."""
        if not (math.isfinite(clear_to_m) and clear_to_m > min_range_m and field_of_view_rad > 0):
            return
        self._apply(sensor_pose, clear_to_m, field_of_view_rad, echo=False)

    def _cone(
        self, sensor_pose: tuple[float, float, float], reach_m: float, half_fov: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The on-grid cells round a reading's cone out to ``reach_m`` and a cell beyond, with each one's
        distance and bearing from the sensor (None: the cone lies off the grid)."""
        sx, sy, syaw = sensor_pose
        outer = reach_m + self.frame.resolution_m
        arc = syaw + np.linspace(-half_fov, half_fov, 9)
        span = np.concatenate([[[sx, sy]], np.stack([sx + outer * np.cos(arc), sy + outer * np.sin(arc)], 1)])
        cells = self.frame.cells_around(span)
        if len(cells) == 0:
            return None
        centres = self.frame.cells_to_world(cells)
        dx, dy = centres[:, 0] - sx, centres[:, 1] - sy
        distance = np.hypot(dx, dy)
        bearing = (np.arctan2(dy, dx) - syaw + math.pi) % (2 * math.pi) - math.pi
        return cells, distance, bearing

    def _cell_half_angle(self, distance: np.ndarray) -> np.ndarray:
        """Each cell's angular half width as seen from a sensor ``distance`` away."""
        reach = self.frame.resolution_m * math.sqrt(0.5)
        return np.arcsin(np.clip(reach / np.maximum(distance, 1e-9), 0.0, 1.0))

    def _evidence(
        self,
        distance: np.ndarray,
        bearing: np.ndarray,
        reach_m: float,
        half_fov: float,
        echo: bool,
        candidates: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """One reading's ``(free, occupied)`` evidence for the cells of its cone (:func:`reading_evidence` on
        this grid: the echo's band a cell wide, a cell reaching half its diagonal and the pose margin)."""
        res = self.frame.resolution_m
        return reading_evidence(
            distance,
            bearing,
            reach_m,
            half_fov,
            echo,
            self.model,
            res,  # the arc crosses cells whose centres lie up to half a cell off it
            candidates=candidates,
            cell_reach_m=res * math.sqrt(0.5) + SENSOR_POSE_MARGIN_M,
        )

    def _apply(
        self, sensor_pose: tuple[float, float, float], reach_m: float, fov_rad: float, echo: bool
    ) -> None:
        sx, sy, syaw = sensor_pose
        half_fov = 0.5 * fov_rad
        cone = self._cone(sensor_pose, reach_m, half_fov)
        if cone is None:
            return
        cells, distance, bearing = cone
        iy, ix = cells[:, 1], cells[:, 0]
        current = self._log_odds[iy, ix]
        # One surface made the echo: arc cells known to be free (seen through from elsewhere) did not, and
        # the evidence goes to the arc cells that may have (the rest of the arc, renormalised).
        candidates = current > self.model.clear_log_odds
        share = 1.0
        if echo:
            # Where on the arc the echo came from, if an earlier echo of the same surface can tell: the
            # evidence goes there whole. If none can, the arc gets part of it for now (see
            # :mod:`services.planner.echo_pairing`), and a later echo that can place it gives the rest.
            heard = Echo(sx, sy, syaw, reach_m, half_fov)
            where = self._pairing.where(heard, bearing, self._cell_half_angle(distance))
            if where is None:
                share = self.model.unplaced_echo_share
            else:
                candidates &= where | (np.abs(bearing) >= half_fov)
            self._resolve_earlier(heard)
            self._pairing.keep(heard, resolved=where is not None)
            current = self._log_odds[iy, ix]
        free, occupied = self._evidence(distance, bearing, reach_m, half_fov, echo, candidates)
        if share < 1.0:
            # Part of the evidence for now, though never so little that the arc no longer counts as heard:
            # what a far echo makes suspect (and slows the robot near) is as before. (Occupied evidence is
            # never negative.)
            occupied = np.maximum(occupied * share, np.minimum(occupied, HEARD_FLOOR_LOG_ODDS))
        # Looked at: every cell whose centre the cone covered, out to the echo. Suspicion ("a pane probably
        # goes on") stays off them, as before the free evidence was limited to cells covered whole: with
        # the cells the cone only grazed counted as never looked at, suspicion round a pane's marks closed
        # the 0.8 m gap between the clutter room's pane and a box, and a robot there found no path.
        touched = (free != 0.0) | (occupied != 0.0) | ((np.abs(bearing) < half_fov) & (distance < reach_m))
        limit = self.model.max_log_odds
        self._log_odds[iy, ix] = np.clip(current + free + occupied, -limit, limit)
        self._seen[iy[touched], ix[touched]] = True
        sensor_cell = self.frame.world_to_cells(np.array([[sx, sy]]))
        if self.frame.cells_in_bounds(sensor_cell).all():
            self._seen[sensor_cell[0, 1], sensor_cell[0, 0]] = True

    def _resolve_earlier(self, newer: Echo) -> None:
        """Earlier echoes no echo could place yet, placed by ``newer``: the rest of their evidence, where
        the two agree they came from."""
        for older in self._pairing.unresolved_near(newer):
            cone = self._cone((older.x, older.y, older.yaw), older.range_m, older.half_fov_rad)
            if cone is None:
                continue
            cells, distance, bearing = cone
            where = placed_by(older, newer, bearing, self._cell_half_angle(distance))
            if where is None:
                continue
            iy, ix = cells[:, 1], cells[:, 0]
            current = self._log_odds[iy, ix]
            candidates = (current > self.model.clear_log_odds) & (
                where | (np.abs(bearing) >= older.half_fov_rad)
            )
            _, occupied = self._evidence(
                distance, bearing, older.range_m, older.half_fov_rad, True, candidates
            )
            limit = self.model.max_log_odds
            self._log_odds[iy, ix] = np.clip(
                current + occupied * (1.0 - self.model.unplaced_echo_share), -limit, limit
            )
            self._pairing.resolved(older)

    def observe_footprint(self, pose: tuple[float, float, float]) -> None:
        """Where the robot stands there is no glass."""
        inside = self.frame.cells_under_rectangle(pose, self.params.robot_length_m, self.params.robot_width_m)
        self._log_odds[inside[:, 1], inside[:, 0]] = -self.model.max_log_odds
        self._seen[inside[:, 1], inside[:, 0]] = True
        self._under_robot = inside

    def observe_turning_circle(self, pose: tuple[float, float, float]) -> None:
        """Within reach of the robot turning in place, suspect nothing unseen (marks stay marks).

        A robot that stopped facing a pane has the pane's marks ahead and, beside the sonar's narrow cone,
        cells it never looked at within ``suspicion_radius_m`` of them: suspected glass within reach of
        its front corners. It could then neither turn (a corner sweeps into them) nor back away (the
        outline the follower checks lies half a cell outside the cells its footprint cleared), and every
        recovery ended the same way. The node calls this when a task starts, with the robot standing
        still, and never while driving: suspicion keeps a moving robot off the unseen end of a pane.
        """
        x, y, _ = pose
        inside = self.frame.cells_within((x, y), self.turning_reach_m)
        self._seen[inside[:, 1], inside[:, 0]] = True

    @property
    def turning_reach_m(self) -> float:
        """How far from its centre the robot's corners sweep when it turns in place, with a cell and a half
        to spare (the footprint's outline is checked half a cell outside it)."""
        return self.params.circumscribed_radius_m + 1.5 * self.frame.resolution_m

    def clear(self) -> None:
        self._forgotten = None
        self._forgotten_glass &= ~self._seen  # what was looked at since its clearing is settled
        self._forgotten_glass |= self._log_odds > SUSPECTED_LOG_ODDS
        self._log_odds[...] = 0.0
        self._seen[...] = False
        self._excused[...] = False
        self._cleared_by_recovery[...] = False
        self._extension_cache = None
        self._heard_line_cache = None
        self._held.clear()
        self._pairing.clear()

    def clear_around(self, xy: tuple[float, float], radius_m: float, keep_within_m: float = 0.0) -> None:
        """Forget evidence and looks within ``radius_m`` of a point but not within ``keep_within_m`` of it;
        glass found farther away stays known."""
        cells = self.frame.cells_within(xy, radius_m)
        if keep_within_m > 0.0 and len(cells):
            centres = self.frame.cells_to_world(cells)
            cells = cells[np.hypot(centres[:, 0] - xy[0], centres[:, 1] - xy[1]) > keep_within_m]
        rows, cols = cells[:, 1], cells[:, 0]
        self._forgotten = (
            cells,
            self._log_odds[rows, cols].copy(),
            self._seen[rows, cols].copy(),
            self._excused[rows, cols].copy(),
            self._cleared_by_recovery[rows, cols].copy(),
        )
        self._forget(cells)

    def restore_unheard(self) -> int:
        """Put back what the last :meth:`clear_around` forgot in the cells the sonar has not covered since;
        how many of them are glass again.

        A recovery forgets the glass round a stuck robot so that its look round hears it afresh. When the
        look round cannot turn (a corner would touch something), nothing is heard again, and a pane's end
        forgotten that way is what the robot, replanning through the floor it left, drove into next.
        """
        if self._forgotten is None:
            return 0
        cells, log_odds, seen, excused, cleared = self._forgotten
        self._forgotten = None
        unheard = ~self._seen[cells[:, 1], cells[:, 0]]
        rows, cols = cells[unheard, 1], cells[unheard, 0]
        self._log_odds[rows, cols] = log_odds[unheard]
        self._seen[rows, cols] = seen[unheard]
        self._excused[rows, cols] = excused[unheard]
        self._cleared_by_recovery[rows, cols] = cleared[unheard]
        self._extension_cache = None
        self._heard_line_cache = None
        return int(np.count_nonzero(log_odds[unheard] >= self.model.mark_log_odds))

    def clear_cells(self, inside: np.ndarray) -> None:
        """Forget evidence and looks in ``inside`` (cells ``(N, 2)``); glass found elsewhere stays known."""
        self._forgotten = None
        self._forget(inside)

    def _forget(self, inside: np.ndarray) -> None:
        if len(inside) == 0:
            return
        self._forgotten_glass &= ~self._seen  # what was looked at since its clearing is settled
        self._forgotten_glass[inside[:, 1], inside[:, 0]] |= (
            self._log_odds[inside[:, 1], inside[:, 0]] > SUSPECTED_LOG_ODDS
        )
        self._log_odds[inside[:, 1], inside[:, 0]] = 0.0
        self._seen[inside[:, 1], inside[:, 0]] = False
        self._excused[inside[:, 1], inside[:, 0]] = False
        self._cleared_by_recovery[inside[:, 1], inside[:, 0]] = True
        self._extension_cache = None
        self._heard_line_cache = None
        self._held.clear()

    def restore(self, layer: np.ndarray) -> None:
        """Adopt a sonar layer kept from before (see :mod:`services.planner.glass_store`): its glass as
        just over the mark threshold, what it had looked at as looked at, with no evidence either way."""
        if layer.shape != self.frame.shape:
            raise ValueError(f"a sonar layer of shape {layer.shape} does not fit the grid {self.frame.shape}")
        marked = layer == LETHAL_OBSTACLE
        self._seen[...] = layer != NO_INFORMATION
        self._log_odds[...] = 0.0
        self._excused[...] = False
        self._log_odds[marked] = min(self.model.mark_log_odds + 0.5, self.model.max_log_odds)

    def suspected_cells_xy(self) -> np.ndarray:
        """Centres ``(N, 2)`` of cells with evidence of glass below the mark threshold: glass the sonar
        has heard but not confirmed."""
        model = self.model
        suspected = (self._log_odds > SUSPECTED_LOG_ODDS) & (self._log_odds < model.mark_log_odds)
        iy, ix = np.nonzero(suspected)
        return self.frame.cells_to_world(np.stack([ix, iy], axis=1))

    def heard_cells_xy(
        self, near_xy: tuple[float, float] | None = None, radius_m: float = math.inf
    ) -> np.ndarray:
        """Centres ``(N, 2)`` of every cell the sonar has heard glass in: suspected, marked, or on a held
        arc, or where a marked pane probably goes on (:meth:`pane_extension_mask`), or heard and forgotten by
        a clearing and not looked at since. The robot slows near them:
        where one pane is known its unheard end is near, and a plan that
        rounds a pane's end keeps changing as the end is heard (the robot once clipped ends at full speed
        while replanning several times a second).

        With ``near_xy``, only the cells in the box bounding the circle of ``radius_m`` round it (some of
        them farther than ``radius_m``, at the box's corners): the slowdown asks at every control tick, and
        searching the whole grid each time is wasted work (measurement 71)."""
        if near_xy is None or not math.isfinite(radius_m):
            rows, cols = slice(0, self.frame.height), slice(0, self.frame.width)
        else:
            rows, cols = self.frame.window_around(near_xy, radius_m)
        heard = self._log_odds[rows, cols] > SUSPECTED_LOG_ODDS
        if self._held:
            heard = heard | self.held_mask()[rows, cols]
        if self.pane_extension_m > 0:
            # Where a pane probably goes on unheard, too: otherwise the robot rounds such ends at full speed
            # (measurement 81).
            heard = heard | self.pane_extension_mask()[rows, cols]
        # And glass a clearing forgot that the sonar has not looked at again: forgotten is not gone.
        heard = heard | (self._forgotten_glass[rows, cols] & ~self._seen[rows, cols])
        iy, ix = np.nonzero(heard)
        return self.frame.cells_to_world(np.stack([ix + cols.start, iy + rows.start], axis=1))

    def set_walls(self, walls: np.ndarray) -> None:
        """The static map's walls (boolean grid). A pane's extension stops a robot's width and a margin
        short of them: a pane may well meet a wall, but an extension that did would close the gap beside
        the pane's end before the sonar has looked, and the planner would find no way round."""
        if walls.shape != self.frame.shape:
            raise ValueError(f"walls of shape {walls.shape} do not fit the grid {self.frame.shape}")
        farthest_m = max(self._robot_gap_m(), self._heard_line_gap_m())
        self._wall_squared = squared_distance_to_marks(walls, farthest_m / self.frame.resolution_m)
        self._extension_cache = None
        self._heard_line_cache = None

    def _robot_gap_m(self) -> float:
        """The gap a pane's extension leaves before a wall or another pane: the robot's width and a margin."""
        return 2.0 * self.params.circumscribed_radius_m + 0.1

    def _heard_line_gap_m(self) -> float:
        """The gap a heard line leaves before a wall or another pane: the robot's gap and the suspicion
        radius, which the line's cells grow by as they seed suspicion. A line stopped only the robot's gap
        short of a wall left its suspicion 0.3 m from the wall, and the robot squeezed past the glass room's
        pane between the two, stopping for "collision ahead" (measurement 117). Beside a wall the robot's
        gap is left whole; beside another pane, whose heard cells seed suspicion of their own, up to the
        radius less."""
        return self._robot_gap_m() + self.suspicion_radius_m

    def pane_extension_mask(self) -> np.ndarray:
        """Boolean ``(height, width)``: where the marked panes probably go on, unseen (see the module doc)."""
        marks = self._log_odds >= self.model.mark_log_odds
        cached = self._extension_cache
        if cached is not None and np.array_equal(cached[0], marks) and np.array_equal(cached[1], self._seen):
            return cached[2]
        extension = self._extend(marks, self._seen, self.pane_extension_m)
        self._extension_cache = (marks, self._seen.copy(), extension)
        return extension

    def _extend(
        self,
        cells: np.ndarray,
        looked_at: np.ndarray,
        reach_m: float,
        max_gap_cells: float = MAX_GAP_CELLS,
        gap_m: float | None = None,
    ) -> np.ndarray:
        """Runs of ``cells`` along lines (gaps of up to ``max_gap_cells`` within a run) carried on for
        ``reach_m`` through floor not ``looked_at``, stopping ``gap_m`` short of walls and of other panes
        (a pane's extension: :meth:`_robot_gap_m`, the default) and at floor a recovery cleared (see
        :func:`pane_extensions`)."""
        gap_m = self._robot_gap_m() if gap_m is None else gap_m
        stops = self._cleared_by_recovery
        if self._wall_squared is not None:
            gap_cells = gap_m / self.frame.resolution_m
            stops = stops | (self._wall_squared <= gap_cells * gap_cells)
        return pane_extensions(
            cells,
            looked_at,
            self.frame.resolution_m,
            reach_m,
            blocked=stops,
            clearance_m=gap_m,
            max_gap_cells=max_gap_cells,
        )

    def heard_line_mask(self, heard: np.ndarray) -> np.ndarray:
        """Boolean ``(height, width)``: where runs of ``heard`` cells along a line would go on, for up to
        :data:`HEARD_LINE_EXTENSION_M` past their ends (never past :attr:`pane_extension_m`), whether or not
        the sonar looked there, stopping short of walls and of other panes by a robot's width and the
        suspicion radius (:meth:`_heard_line_gap_m`). It only seeds suspicion (see the module doc): on its
        own it is not glass."""
        reach_m = min(self.pane_extension_m, HEARD_LINE_EXTENSION_M)
        if reach_m <= 0:
            return np.zeros_like(heard)
        cached = self._heard_line_cache
        if cached is not None:
            before, line, near_line = cached
            changed = before ^ heard
            if (
                np.count_nonzero(changed)
                <= max(HEARD_LINE_REUSE_CELLS, HEARD_LINE_REUSE_SHARE * np.count_nonzero(heard))
                and not (changed & heard & near_line).any()
            ):
                return line
        gap_cells = HEARD_LINE_MAX_GAP_M / self.frame.resolution_m
        line = self._extend(
            heard, np.zeros_like(heard), reach_m, max_gap_cells=gap_cells, gap_m=self._heard_line_gap_m()
        )
        near_line = squared_distance_to_marks(line, HEARD_LINE_NEAR_CELLS) <= HEARD_LINE_NEAR_CELLS**2
        self._heard_line_cache = (heard.copy(), line, near_line)
        return line

    def suspicion_mask(self, radius_share: float = 1.0) -> np.ndarray:
        """Boolean ``(height, width)``: the floor suspected of glass, unlooked-at and within the suspicion
        radius (times ``radius_share``) of a cell the sonar heard glass in or of a heard run's line (see
        :meth:`glass_mask`). Where :meth:`excuse_suspicion` let the robot pass, only the inner
        :data:`EXCUSED_RADIUS_SHARE` of the radius is suspected."""
        heard = self._log_odds > SUSPECTED_LOG_ODDS
        if self.suspicion_radius_m <= 0 or radius_share <= 0 or not heard.any():
            return np.zeros(self.frame.shape, dtype=bool)
        radius_cells = radius_share * self.suspicion_radius_m / self.frame.resolution_m
        seeds = heard | self.heard_line_mask(heard)
        squared = squared_distance_to_marks(seeds, radius_cells)
        near = squared <= radius_cells * radius_cells
        if self._excused.any():
            inner = EXCUSED_RADIUS_SHARE * self.suspicion_radius_m / self.frame.resolution_m
            near &= ~self._excused | (squared <= inner * inner)
        return near & ~self._seen

    def excuse_suspicion(self, cells: np.ndarray) -> int:
        """Suspect ``cells`` (boolean ``(height, width)``) only within :data:`EXCUSED_RADIUS_SHARE` of the
        suspicion radius from heard glass; how many cells that took out of suspicion.

        For the planner, when suspicion alone closes every way to its goal (see
        :mod:`services.planner.suspicion_way`): the robot may then drive where it was only guessed, and
        its sonar looks there on the way. The cells stay glass if marked, held or on a pane's extension,
        and become glass again when the sonar marks them; only the outer part of the guess is dropped,
        until the memory forgets them (:meth:`clear`, :meth:`clear_cells`)."""
        before = self.suspicion_mask()
        self._excused |= np.asarray(cells, dtype=bool) & before
        return int(np.count_nonzero(before & ~self.suspicion_mask()))

    def glass_mask(self, suspicion_share: float = 1.0) -> np.ndarray:
        """Boolean ``(height, width)``: marked by the sonar, unlooked-at within the suspicion radius (times
        ``suspicion_share``) of a cell the sonar heard glass in (marked or suspected), a marked pane's
        unseen continuation (see :meth:`pane_extension_mask`), or on a held arc.

        Suspicion grows from every heard cell, not only from marks: rounding a pane's end seen obliquely,
        the last marks lay short of the end and the cells between held only echoes from the cone's edge,
        too weak to mark. Suspicion from the marks alone stopped short of the end, and the robot's front
        corner clipped it (measurement 68). It grows from where a heard run's line goes on, too
        (:meth:`heard_line_mask`)."""
        glass = (self._log_odds >= self.model.mark_log_odds) | self.suspicion_mask(suspicion_share)
        if self.pane_extension_m > 0:
            glass = glass | self.pane_extension_mask()
        if self._held:
            glass = glass | self.held_mask()
        return glass
