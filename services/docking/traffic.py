"""Traffic between robots sharing a room: who gives way when two meet, and where it waits.

Planners already treat other robots as obstacles (their lidar sees them), which is enough in open
space. In a doorway or a corridor one robot wide it is not: two robots meeting head-on each block the
other's only way, and both wait for ever. The rule:

- **Priority** goes to the robot with less charge (it needs a dock more), then to the name that sorts
  first. Every robot knows every other's charge from the bus, so both reach the same verdict.
- Two robots **meet** when each is ahead of the other (within :data:`HEAD_ON_HALF_ANGLE_RAD` of its
  heading) and they are closer than :data:`MEET_DISTANCE_M`, both under way.
- The robot without priority **gives way**: it goes to the nearest **passing place** by free path
  (:func:`passing_place`): a spot clear of the walls, off the other robot's way (its plan ahead, or
  the line it heads along), and out of its reach; there it waits until the other has gone by (it no
  longer heads at the robot), then carries on with what it was doing.
- Robots whose ways **cross** (the other robot closer than :data:`CROSSING_DISTANCE_M` and in front,
  within :data:`CROSSING_HALF_ANGLE_RAD` of the heading, but not head-on): the one without priority
  stops where it is until the other is out of its way. Each planner's collision check sees the other
  robot only where it is now, not where it is going, so two robots crossing could otherwise meet side
  on; a robot standing still is an obstacle the other's planner does avoid.

Pure: no bus, no clock. The docking node keeps the peers' latest poses, charges and plans, asks
:func:`must_give_way` each tick while its robot is under way, and runs :class:`GiveWay` when it says so.
"""

from __future__ import annotations

import enum
import math
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from services.docking.task_io import Intent, Navigate, NavOutcome, Outcome, Task, TickInputs
from shared.geometry import Pose2D, distances_to_segment, wrap_angle

#: Two robots closer than this, each ahead of the other, meet.
MEET_DISTANCE_M = 1.6
HEAD_ON_HALF_ANGLE_RAD = math.radians(50.0)
#: Another robot this close and in front, within this angle of the heading, is crossing the robot's way.
CROSSING_DISTANCE_M = 1.0
CROSSING_HALF_ANGLE_RAD = math.radians(70.0)
#: A passing place: this far from the other robot's way and from the other robot itself ...
CLEAR_OF_WAY_M = 0.7
CLEAR_OF_ROBOT_M = 1.0
#: ... and this far from every wall (a little more than the robot's half diagonal, 0.25 m).
WALL_CLEARANCE_M = 0.3
#: How far round the robot passing places are looked for, and on how fine a grid.
SEARCH_RADIUS_M = 4.0
GRID_M = 0.1
#: The other robot's way: its plan this far ahead, or (no fresh plan) the line it heads along.
WAY_AHEAD_M = 5.0
#: Giving way ends when the other robot no longer heads at the robot (it has gone by, or turned away),
#: or is this far away ...
CLEAR_DISTANCE_M = 4.0
#: ... or after this long, whatever happened (then the rule is asked again).
GIVE_WAY_TIMEOUT_S = 60.0


@dataclass(frozen=True, slots=True)
class Peer:
    """Another robot as the bus tells of it: where it is, its charge, its plan ahead (map frame)."""

    name: str
    pose: Pose2D
    battery: float
    under_way: bool
    plan: np.ndarray | None = None


def has_priority(name: str, battery: float, other_name: str, other_battery: float) -> bool:
    """Less charge first, then the name that sorts first."""
    return (battery, name) < (other_battery, other_name)


def _ahead(of: Pose2D, point: Pose2D, half_angle_rad: float = HEAD_ON_HALF_ANGLE_RAD) -> bool:
    bearing = math.atan2(point.y - of.y, point.x - of.x)
    return abs(wrap_angle(bearing - of.yaw)) <= half_angle_rad


class Meeting(enum.Enum):
    #: Each ahead of the other: the one without priority goes to a passing place.
    HEAD_ON = "head-on"
    #: The other in front, crossing: the one without priority stops until it is out of the way.
    CROSSING = "crossing"


def must_give_way(me: Pose2D, name: str, battery: float, peers: Iterable[Peer]) -> tuple[Peer, Meeting] | None:
    """The robot this one must give way to now, if any (the nearest), and how they meet."""
    found: list[tuple[float, Peer, Meeting]] = []
    for p in peers:
        if not p.under_way or has_priority(name, battery, p.name, p.battery):
            continue
        distance = me.distance_to(p.pose)
        if distance < MEET_DISTANCE_M and _ahead(me, p.pose) and _ahead(p.pose, me):
            found.append((distance, p, Meeting.HEAD_ON))
        elif distance < CROSSING_DISTANCE_M and _ahead(me, p.pose, CROSSING_HALF_ANGLE_RAD):
            found.append((distance, p, Meeting.CROSSING))
    if not found:
        return None
    _, peer, meeting = min(found, key=lambda f: f[0])
    return peer, meeting


def peer_way(peer: Peer) -> np.ndarray:
    """Points along the other robot's way ahead: its plan's first metres, else the line it heads along."""
    if peer.plan is not None and len(peer.plan) >= 2:
        steps = np.hypot(*np.diff(peer.plan, axis=0).T)
        within = np.concatenate([[0.0], np.cumsum(steps)]) <= WAY_AHEAD_M
        points = peer.plan[within]
        if len(points) >= 2:
            return np.vstack([[peer.pose.x, peer.pose.y], points])
    ends = [peer.pose.transform_point(d, 0.0) for d in np.linspace(0.0, WAY_AHEAD_M, 11)]
    return np.asarray(ends, dtype=float)


def _distance_to_polyline(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    best = np.full(len(points), np.inf)
    for a, b in zip(line[:-1], line[1:]):
        best = np.minimum(best, distances_to_segment(points, a, b))
    return best


def passing_place(me: Pose2D, peer: Peer, walls: Sequence[tuple[tuple[float, float], tuple[float, float]]]) -> Pose2D | None:
    """The passing place nearest ``me`` by free path (a grid search round the robot), or None."""
    n = int(round(2 * SEARCH_RADIUS_M / GRID_M)) + 1
    offsets = (np.arange(n) - n // 2) * GRID_M
    xs, ys = np.meshgrid(me.x + offsets, me.y + offsets)
    cells = np.column_stack([xs.ravel(), ys.ravel()])
    clearance = np.full(len(cells), np.inf)
    for start_xy, end_xy in walls:
        clearance = np.minimum(clearance, distances_to_segment(cells, np.asarray(start_xy, float),
                                                               np.asarray(end_xy, float)))
    to_peer = np.hypot(cells[:, 0] - peer.pose.x, cells[:, 1] - peer.pose.y)
    # Free to move through: clear of the walls and of the other robot's body (with the robots' size).
    free = (clearance >= WALL_CLEARANCE_M - 0.05) & (to_peer >= 0.55)
    way = _distance_to_polyline(cells, peer_way(peer))
    good = free & (clearance >= WALL_CLEARANCE_M) & (way >= CLEAR_OF_WAY_M) & (to_peer >= CLEAR_OF_ROBOT_M)
    free_grid, good_grid = free.reshape(n, n), good.reshape(n, n)
    start = (n // 2, n // 2)
    free_grid[start] = True  # the robot stands there
    distance = np.full((n, n), -1, dtype=int)
    distance[start] = 0
    frontier = deque([start])
    while frontier:
        i, j = frontier.popleft()
        if good_grid[i, j]:
            return Pose2D(float(xs[i, j]), float(ys[i, j]), me.yaw)
        for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)):
            ni, nj = i + di, j + dj
            if 0 <= ni < n and 0 <= nj < n and distance[ni, nj] < 0 and free_grid[ni, nj]:
                distance[ni, nj] = distance[i, j] + 1
                frontier.append((ni, nj))
    return None


class GiveWayPhase(enum.Enum):
    GOING = "going to the passing place"
    WAITING = "waiting for the other robot to pass"


class GiveWay(Task[GiveWayPhase]):
    """Go to the passing place (``place``; None: stop where it is) and wait there until ``peer`` has gone
    by (see the module docstring).

    Succeeds once the way is clear (or after :data:`GIVE_WAY_TIMEOUT_S`); the node then carries on with
    the task it interrupted. The node tells it each tick where the other robot is (:meth:`peer_seen`).
    """

    def __init__(self, peer: str, place: Pose2D | None, resume: object) -> None:
        super().__init__(GiveWayPhase.GOING if place is not None else GiveWayPhase.WAITING)
        self.peer = peer
        self.place = place
        #: What to carry on with afterwards (for the node: the interrupted task's request).
        self.resume = resume
        self._peer_pose: Pose2D | None = None
        self._key = self.new_nav_key()

    def peer_seen(self, pose: Pose2D | None) -> None:
        self._peer_pose = pose

    def _clear(self, me: Pose2D | None) -> bool:
        peer = self._peer_pose
        if peer is None or me is None:
            return True  # the other robot is gone from the bus: nothing to wait for
        if self.place is None:  # stopped for a crossing: until the other is out of the way in front
            return (me.distance_to(peer) >= CROSSING_DISTANCE_M + 0.2
                    or not _ahead(me, peer, CROSSING_HALF_ANGLE_RAD + math.radians(10.0)))
        return me.distance_to(peer) >= CLEAR_DISTANCE_M or not _ahead(peer, me)

    def tick(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        if self.started_s is not None and now - self.started_s >= GIVE_WAY_TIMEOUT_S:
            self.finish(Outcome.SUCCEEDED, message="gave way for the longest allowed")
            return None
        if self.phase is GiveWayPhase.GOING and self.place is not None:
            outcome = inputs.nav.finished(self._key)
            if outcome is None:
                return Navigate(self.place, self._key)
            self.enter(GiveWayPhase.WAITING, now)
            if outcome is not NavOutcome.SUCCEEDED:
                self.message = "short of the passing place"
        if self._clear(inputs.robot_pose):
            self.finish(Outcome.SUCCEEDED, message=f"{self.peer} has gone by")
            return None
        self.holding = f"giving way to {self.peer}"
        return None
