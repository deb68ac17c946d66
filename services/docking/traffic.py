"""Traffic between robots sharing a room: who gives way when two meet, and where it waits.

Planners already treat other robots as obstacles (their lidar sees them), which is enough in open
space. In a doorway or a corridor one robot wide it is not: two robots meeting head-on each block the
other's only way, and both plan, back up and give up for ever. The rule:

- **Priority** goes to the robot with less charge (it needs a dock more), then to the name that sorts
  first. Every robot knows every other's charge from the bus, so both reach the same verdict.
- Two robots **meet head-on** when each is ahead of the other (within :data:`HEAD_ON_HALF_ANGLE_RAD`
  of its heading), closer than :data:`MEET_DISTANCE_M`, both under way, each on the other's way, and
  the way between them is **narrow** (it passes closer than :data:`NARROW_CLEARANCE_M` to a wall: no
  room to pass side by side). The way of the robot with priority is its own plan's next metres where
  it follows one (:func:`way_ahead`), else the line it heads along: a robot standing at its passing
  place beside the end of that plan is in nobody's way, though it stands on the line.
  The one without priority goes to the nearest **passing place** by free path (:func:`passing_place`):
  a spot clear of the walls, off the other robot's way (its plan ahead, or the line it heads along),
  and out of its reach; there it waits until the other no longer heads at it (it has gone by), then
  carries on with what it was doing; so it does too should the other drive past before it gets there
  (it is behind the other, which stands on its far side from where they met). Should this one still be
  on its way to the passing place after :data:`STILL_GIVING_WAY_S` (the way there can be blocked) while
  the other has gone its way or stopped driving, it carries on. The one with priority stops meanwhile
  and waits until the way ahead is clear, so that it does not plan, back up and give up while the
  other backs out.
- Robots whose ways **cross** (the other robot closer than :data:`CROSSING_DISTANCE_M` and in front,
  within :data:`CROSSING_HALF_ANGLE_RAD` of the heading, not head-on): the one without priority stops
  where it is until the other is out of its way. Each planner's collision check sees the other robot
  only where it is now, not where it is going, so two robots crossing could otherwise meet side on; a
  robot standing still is an obstacle the other's planner does avoid.
- **Too close** (another robot within :data:`TOO_CLOSE_M` in front): even the robot with priority
  stops, for :data:`TOO_CLOSE_STOP_S`, so that its planner sees the other standing still before it
  drives on round it; then it does not stop for that robot again for :data:`TOO_CLOSE_CALM_S`.
- **Nobody moves.** A wait ends when the way clears, and the robot waited for must move for it to clear.
  What each robot knows of the other comes late, so both can wait on each other (the one with priority
  sees the one giving way still on the line it heads along, which turned after the passing place was
  chosen), or the robot waited for can be held up by something else, even by the robot waiting for it
  (a robot stopped for a crossing stands where the other's planner finds no way). So a robot that waits
  watches the other: once the other has stood within :data:`PEER_STILL_M` for :data:`STILL_PRIORITY_S`
  (with priority) or :data:`STILL_GIVING_WAY_S` (without), it carries on; its planner goes round a
  robot standing still. The times differ so that of two robots waiting on each other the one with
  priority moves first, and the other sees it move. A robot that has not been giving way itself for
  :data:`STILL_PRIORITY_S` waits for nobody: standing still, it is stuck (its planner finds no way,
  often past the robot giving way to it), so the robot giving way carries on after
  :data:`STILL_PRIORITY_S` too. After such a wait, or one that ran to its time
  limit, the robot does not stop for the same robot again for :data:`CARRY_ON_S`.

Pure: no bus, no clock. The docking node keeps the peers' latest poses, charges and plans, asks
:func:`must_give_way` each tick while its robot is under way, and runs :class:`GiveWay` when it says so.
"""

from __future__ import annotations

import enum
import math
from collections import deque
from collections.abc import Callable, Container, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from services.docking.task_io import Intent, Navigate, NavOutcome, Outcome, Task, TickInputs
from shared.geometry import Pose2D, distances_to_segment, wrap_angle

#: Two robots closer than this, each ahead of the other, in a narrow way, meet head-on (a planner
#: gives up on a corridor with a robot in it from about 3 m).
MEET_DISTANCE_M = 3.5
#: The way between two robots is narrow when it passes this close to a wall.
NARROW_CLEARANCE_M = 0.65
HEAD_ON_HALF_ANGLE_RAD = math.radians(50.0)
#: Another robot this close and in front, within this angle of the heading, is crossing the robot's way.
CROSSING_DISTANCE_M = 1.2
CROSSING_HALF_ANGLE_RAD = math.radians(70.0)
#: Another robot this close in front (centre to centre, within this angle) makes even a robot with
#: priority stop for a moment, then leave the rest to its planner for a while.
TOO_CLOSE_M = 0.8
TOO_CLOSE_HALF_ANGLE_RAD = math.radians(60.0)
TOO_CLOSE_STOP_S = 1.5
TOO_CLOSE_CALM_S = 6.0
#: A passing place: this far from the other robot's way and from the other robot itself ...
CLEAR_OF_WAY_M = 0.7
CLEAR_OF_ROBOT_M = 1.0
#: A passing place keeps this much more from the other's way than the other checks for when it waits for
#: a clear way, so that a robot standing at its passing place always counts as out of the way.
PLACE_MARGIN_M = 0.25
#: ... and this far from every wall (a little more than the robot's half diagonal, 0.25 m).
WALL_CLEARANCE_M = 0.3
#: How far round the robot passing places are looked for, and on how fine a grid.
SEARCH_RADIUS_M = 4.0
GRID_M = 0.1
#: The other robot's way: its plan this far ahead, or (no fresh plan) the line it heads along.
WAY_AHEAD_M = 5.0
#: A plan that passes farther than this from the robot is not what it follows now (an old one).
ON_PLAN_M = 0.5
#: Giving way ends when the other robot no longer heads at the robot (it has gone by, or turned away),
#: or is this far away ...
CLEAR_DISTANCE_M = 4.0
#: ... or after this long, whatever happened (then the rule is asked again).
GIVE_WAY_TIMEOUT_S = 60.0
#: The robot with priority waits at most this long for the other to back out.
PRIORITY_WAIT_TIMEOUT_S = 30.0
#: Giving way lasts at least this long (sim seconds): what the robot knows of the other comes late and
#: noisy, and a rule that flips every tick stops and starts both robots instead of letting one pass.
MIN_GIVE_WAY_S = 1.0
#: The other robot stands still when it stays within this of where it stood: a robot blocked, backing up
#: (0.15 m a recovery) and creeping forward again as it replans, stays within it; one driving by leaves it
#: within 3 s ...
PEER_STILL_M = 0.75
#: ... for this long (sim seconds): then a robot waiting with priority carries on ...
STILL_PRIORITY_S = 6.0
#: ... and, later, one giving way: of two robots waiting on each other, the one with priority moves first.
STILL_GIVING_WAY_S = 12.0
#: After a wait that ended without the way clearing, the robot does not stop for that robot for this long.
CARRY_ON_S = 10.0


#: A peer's plan: its points (map frame), or a function that gives them when first asked. The rule
#: looks at plans only of robots near and face to face, so the docking node hands plans on undecoded
#: (decoding and validating a plan is dear, and every peer sends one at each replan: measurement 65).
PlanPoints = np.ndarray | Callable[[], np.ndarray | None] | None


@dataclass(frozen=True, slots=True)
class Peer:
    """Another robot as the bus tells of it: where it is, its charge, its plan ahead (map frame)."""

    name: str
    pose: Pose2D
    battery: float
    under_way: bool
    plan: PlanPoints = None
    #: It is giving way (or waiting for its way to clear) itself.
    giving_way: bool = False

    def plan_points(self) -> np.ndarray | None:
        """The plan's points, decoded now if they came as a function."""
        return plan_points(self.plan)

    @property
    def active(self) -> bool:
        """Driving, or giving way itself: a robot worth waiting for (one parked or docked is not)."""
        return self.under_way or self.giving_way


def plan_points(plan: PlanPoints) -> np.ndarray | None:
    """A plan's points, decoded now if they came as a function."""
    return plan() if callable(plan) else plan


def has_priority(name: str, battery: float, other_name: str, other_battery: float) -> bool:
    """Less charge first, then the name that sorts first."""
    return (battery, name) < (other_battery, other_name)


def _ahead(of: Pose2D, point: Pose2D, half_angle_rad: float = HEAD_ON_HALF_ANGLE_RAD) -> bool:
    bearing = math.atan2(point.y - of.y, point.x - of.x)
    return abs(wrap_angle(bearing - of.yaw)) <= half_angle_rad


class Meeting(enum.Enum):
    #: Head-on in a narrow way, without priority: back out to a passing place.
    HEAD_ON = "head-on"
    #: Head-on in a narrow way, with priority: stop until the other has backed out of the way.
    HEAD_ON_PRIORITY = "head-on, with priority"
    #: The other in front, crossing, without priority: stop until it is out of the way.
    CROSSING = "crossing"
    #: The other very close in front, with priority: stop for a moment, then let the planner go round.
    TOO_CLOSE = "too close"


Walls = Sequence[tuple[tuple[float, float], tuple[float, float]]]


def clearance_between(a: Pose2D, b: Pose2D, walls: Walls) -> float:
    """The least distance to a wall along the straight way from ``a`` to ``b``."""
    steps = max(2, int(a.distance_to(b) / 0.1) + 1)
    points = np.column_stack([np.linspace(a.x, b.x, steps), np.linspace(a.y, b.y, steps)])
    least = math.inf
    for start_xy, end_xy in walls:
        least = min(
            least,
            float(distances_to_segment(points, np.asarray(start_xy, float), np.asarray(end_xy, float)).min()),
        )
    return least


def must_give_way(
    me: Pose2D,
    name: str,
    battery: float,
    peers: Iterable[Peer],
    walls: Walls,
    calm: Container[str] = (),
    carry_on: Container[str] = (),
    own_plan: PlanPoints = None,
) -> tuple[Peer, Meeting] | None:
    """The robot this one must give way to (or wait for) now, if any (the nearest), and how they meet;
    ``calm``: robots this one stopped for lately as too close, not stopped for again yet; ``carry_on``:
    robots this one waited for lately without the way clearing, not waited for again yet; ``own_plan``:
    this robot's plan (see :func:`way_ahead`), looked at only for a robot met face to face."""
    found: list[tuple[float, Peer, Meeting]] = []
    own_way: list[np.ndarray] = []

    def my_way() -> np.ndarray:
        if not own_way:
            own_way.append(way_ahead(me, plan_points(own_plan)))
        return own_way[0]

    for p in peers:
        if not (p.under_way or p.giving_way) or p.name in carry_on:
            continue
        priority = has_priority(name, battery, p.name, p.battery)
        distance = me.distance_to(p.pose)
        # The cheap tests first: the ways and the walls are measured only for robots near and face to face.
        if (
            distance < MEET_DISTANCE_M
            and _ahead(me, p.pose)
            and _ahead(p.pose, me)
            and _in_each_others_way(me, p, priority, my_way)
            and clearance_between(me, p.pose, walls) < NARROW_CLEARANCE_M
        ):
            found.append((distance, p, Meeting.HEAD_ON_PRIORITY if priority else Meeting.HEAD_ON))
        elif (
            not priority
            and p.under_way
            and distance < CROSSING_DISTANCE_M
            and _ahead(me, p.pose, CROSSING_HALF_ANGLE_RAD)
        ):
            found.append((distance, p, Meeting.CROSSING))
        elif (
            priority
            and p.name not in calm
            and distance < TOO_CLOSE_M
            and _ahead(me, p.pose, TOO_CLOSE_HALF_ANGLE_RAD)
        ):
            found.append((distance, p, Meeting.TOO_CLOSE))
    if not found:
        return None
    _, peer, meeting = min(found, key=lambda f: f[0])
    return peer, meeting


def _in_each_others_way(me: Pose2D, peer: Peer, priority: bool, my_way: Callable[[], np.ndarray]) -> bool:
    """Without priority, this robot stands on the other's way ahead; with it, the other stands on this
    one's way ahead (what its wait for a clear way checks)."""
    if priority:
        return _off_line(peer.pose, my_way()) < CLEAR_OF_WAY_M
    return float(_off_ways(np.array([[me.x, me.y]]), peer_way(peer))[0]) < CLEAR_OF_WAY_M


def way_ahead(me: Pose2D, plan: np.ndarray | None) -> np.ndarray:
    """This robot's way ahead, as a polyline: its plan's next :data:`MEET_DISTANCE_M` from the plan's point
    nearest the robot, when the plan passes within :data:`ON_PLAN_M` of it; else the line it heads along.

    The plan says where the robot will drive: the heading line runs on past the plan's end, and across a
    corner the plan turns. With the line alone, a robot with priority going to a waypoint beside another's
    passing place met that robot again at its passing place, each waiting for the other to move."""
    if plan is None or len(plan) < 2:
        return _heading_line(me)
    offsets = np.hypot(plan[:, 0] - me.x, plan[:, 1] - me.y)
    nearest = int(np.argmin(offsets))
    if offsets[nearest] > ON_PLAN_M:
        return _heading_line(me)
    rest = plan[nearest:]
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(rest, axis=0).T))])
    return np.vstack([[me.x, me.y], rest[along <= MEET_DISTANCE_M]])


def peer_way(peer: Peer) -> list[np.ndarray]:
    """The other robot's way ahead, as polylines: the line it heads along, and its plan's first metres
    (a planner that has given up on a blocked corridor may hold a plan elsewhere; the heading still
    says where it wants to go)."""
    ends = [peer.pose.transform_point(d, 0.0) for d in np.linspace(0.0, WAY_AHEAD_M, 11)]
    ways = [np.asarray(ends, dtype=float)]
    plan = peer.plan_points()
    if plan is not None and len(plan) >= 2:
        steps = np.hypot(*np.diff(plan, axis=0).T)
        within = np.concatenate([[0.0], np.cumsum(steps)]) <= WAY_AHEAD_M
        points = plan[within]
        if len(points) >= 2:
            ways.append(np.vstack([[peer.pose.x, peer.pose.y], points]))
    return ways


def _off_ways(points: np.ndarray, ways: list[np.ndarray]) -> np.ndarray:
    return np.min([_distance_to_polyline(points, way) for way in ways], axis=0)


def _heading_line(pose: Pose2D) -> np.ndarray:
    return np.asarray(
        [pose.transform_point(d, 0.0) for d in np.linspace(0.0, MEET_DISTANCE_M, 8)], dtype=float
    )


def _off_line(pose: Pose2D, line: np.ndarray) -> float:
    return float(_distance_to_polyline(np.array([[pose.x, pose.y]]), line)[0])


def _distance_to_polyline(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    best = np.full(len(points), np.inf)
    for a, b in zip(line[:-1], line[1:]):
        best = np.minimum(best, distances_to_segment(points, a, b))
    return best


def passing_place(me: Pose2D, peer: Peer, walls: Walls) -> Pose2D | None:
    """The passing place nearest ``me`` by free path (a grid search round the robot), or None."""
    n = int(round(2 * SEARCH_RADIUS_M / GRID_M)) + 1
    offsets = (np.arange(n) - n // 2) * GRID_M
    xs, ys = np.meshgrid(me.x + offsets, me.y + offsets)
    cells = np.column_stack([xs.ravel(), ys.ravel()])
    clearance = np.full(len(cells), np.inf)
    for start_xy, end_xy in walls:
        clearance = np.minimum(
            clearance, distances_to_segment(cells, np.asarray(start_xy, float), np.asarray(end_xy, float))
        )
    to_peer = np.hypot(cells[:, 0] - peer.pose.x, cells[:, 1] - peer.pose.y)
    # Free to move through: clear of the walls and of the other robot's body (with the robots' size).
    free = (clearance >= WALL_CLEARANCE_M - 0.05) & (to_peer >= 0.55)
    way = _off_ways(cells, peer_way(peer))
    good = (
        free
        & (clearance >= WALL_CLEARANCE_M)
        & (way >= CLEAR_OF_WAY_M + PLACE_MARGIN_M)
        & (to_peer >= CLEAR_OF_ROBOT_M)
    )
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
    """What a meeting asks of this robot (see the module docstring): go to the passing place (``place``)
    and wait there until ``peer`` has gone by, or stop where it is until ``peer`` is out of its way.

    Succeeds once the way is clear (or after a timeout); the node then carries on with the task it
    interrupted. The node tells it each tick where the other robot is (:meth:`peer_seen`).
    """

    def __init__(
        self,
        peer: Peer,
        meeting: Meeting,
        place: Pose2D | None,
        resume: object,
        own_way: np.ndarray | None = None,
    ) -> None:
        super().__init__(GiveWayPhase.GOING if place is not None else GiveWayPhase.WAITING)
        self.peer = peer.name
        self.meeting = meeting
        self.place = place
        #: With priority: the way this robot was to drive when they met (:func:`way_ahead`), which the
        #: other must be off for the wait to end; None: the line it heads along.
        self.own_way = own_way
        #: What to carry on with afterwards (for the node: the interrupted task's request).
        self.resume = resume
        #: It ended without the way clearing (the other stood still, or the time limit): the node then
        #: leaves that robot to the planner for a while (:data:`CARRY_ON_S`).
        self.unresolved = False
        self._peer_pose: Pose2D | None = peer.pose
        #: Whether the other robot gives way itself (waits), and when it was last seen to (sim seconds).
        self._peer_giving_way = peer.giving_way
        self._peer_gave_way_s = -math.inf
        #: Where the other robot was when they met: past this robot once on its far side (:meth:`_passed`).
        self._met_at = peer.pose
        #: Where the other robot stood when last seen to move, and since when (sim seconds).
        self._peer_anchor: Pose2D | None = None
        self._peer_still_since = 0.0
        self._key = self.new_nav_key()

    def state_name(self) -> str:
        return "GIVING_WAY"

    def peer_seen(self, pose: Pose2D | None, active: bool = True, giving_way: bool | None = None) -> None:
        """Where the other robot is now, and whether it is still under way or giving way itself (a robot
        that stopped driving, docked or parked, is nothing to wait for); ``giving_way``: whether it gives
        way (waits) itself, None: as it was."""
        self._peer_pose = pose if active else None
        if giving_way is not None:
            self._peer_giving_way = giving_way

    def _patience_s(self, now: float) -> float:
        """How long the other robot may stand still before this one carries on (see the module docstring);
        called every tick, as it notes when the other was last seen giving way."""
        if self._peer_giving_way:
            self._peer_gave_way_s = now
        if self.meeting is Meeting.HEAD_ON_PRIORITY or now - self._peer_gave_way_s >= STILL_PRIORITY_S:
            return STILL_PRIORITY_S
        return STILL_GIVING_WAY_S

    def _peer_still_s(self, now: float) -> float:
        """How long the other robot has stood within :data:`PEER_STILL_M` of one spot (0 while it moves)."""
        pose = self._peer_pose
        if pose is None:
            self._peer_anchor = None
            return 0.0
        if self._peer_anchor is None or self._peer_anchor.distance_to(pose) >= PEER_STILL_M:
            self._peer_anchor, self._peer_still_since = pose, now
        return now - self._peer_still_since

    def _gone(self, me: Pose2D | None) -> bool:
        """The other robot stopped driving, or is :data:`CLEAR_DISTANCE_M` away: no need to make room."""
        peer = self._peer_pose
        return peer is None or (me is not None and me.distance_to(peer) >= CLEAR_DISTANCE_M)

    def _passed(self, me: Pose2D | None) -> bool:
        """The other robot has driven past this one: this robot is behind it, and it stands on this robot's
        far side from where they met. One that turned round where it met this robot is not past it (it
        may turn back)."""
        peer = self._peer_pose
        if peer is None or me is None or _ahead(peer, me, math.pi / 2):
            return False
        met = self._met_at
        return (peer.x - me.x) * (met.x - me.x) + (peer.y - me.y) * (met.y - me.y) < 0.0

    def _clear(self, me: Pose2D | None) -> bool:
        peer = self._peer_pose
        if peer is None:
            return True  # the other robot is gone from the bus, or stopped driving: nothing to wait for
        if me is None:
            return False  # this robot's own pose is stale: wait until it knows where it is
        if self.meeting is Meeting.HEAD_ON_PRIORITY:  # until the other is off the way ahead
            way = self.own_way if self.own_way is not None else _heading_line(me)
            off_way = _off_line(peer, way) >= CLEAR_OF_WAY_M
            return off_way or not _ahead(me, peer) or me.distance_to(peer) >= CLEAR_DISTANCE_M
        if self.place is None:  # stopped for a crossing: until the other is out of the way in front
            return me.distance_to(peer) >= CROSSING_DISTANCE_M + 0.2 or not _ahead(
                me, peer, CROSSING_HALF_ANGLE_RAD + math.radians(10.0)
            )
        return self._gone(me) or not _ahead(peer, me)

    def tick(self, inputs: TickInputs) -> Intent:
        now = inputs.now_s
        limit = PRIORITY_WAIT_TIMEOUT_S if self.meeting is Meeting.HEAD_ON_PRIORITY else GIVE_WAY_TIMEOUT_S
        if self.started_s is not None and now - self.started_s >= limit:
            self.unresolved = True
            self.finish(Outcome.SUCCEEDED, message="gave way for the longest allowed")
            return None
        still_s = self._peer_still_s(now)
        patience = self._patience_s(now)
        held_s = now - self.started_s if self.started_s is not None else 0.0
        if self.phase is GiveWayPhase.GOING and self.place is not None:
            outcome = inputs.nav.finished(self._key)
            if outcome is None:
                if held_s >= MIN_GIVE_WAY_S and self._passed(inputs.robot_pose):
                    # Driven past while this one was still on its way to the passing place (the way there
                    # can be blocked, by the other robot itself): the room is made, nothing to wait for.
                    self.finish(Outcome.SUCCEEDED, message=f"{self.peer} drove past before the passing place")
                    return None
                if held_s >= STILL_GIVING_WAY_S and self._gone(inputs.robot_pose):
                    # The way to the passing place can stay blocked for as long as the other stays away.
                    # Not sooner: a robot that passes 4 m away while this one backs out may turn back.
                    self.unresolved = True
                    self.finish(
                        Outcome.SUCCEEDED, message=f"{self.peer} went its way before the passing place"
                    )
                    return None
                return Navigate(self.place, self._key)
            self.enter(GiveWayPhase.WAITING, now)
            if outcome is not NavOutcome.SUCCEEDED:
                self.message = "short of the passing place"
        if self.meeting is Meeting.TOO_CLOSE:
            if held_s >= TOO_CLOSE_STOP_S:
                self.finish(Outcome.SUCCEEDED, message=f"stopped {held_s:.1f} s for {self.peer}, too close")
                return None
            return self.hold(f"{self.peer} is too close in front")
        if held_s >= MIN_GIVE_WAY_S and self._clear(inputs.robot_pose):
            self.finish(Outcome.SUCCEEDED, message=f"{self.peer} has gone by")
            return None
        if min(still_s, held_s) >= patience:
            self.unresolved = True
            self.finish(
                Outcome.SUCCEEDED, message=f"{self.peer} stood still for {still_s:.1f} s: carrying on"
            )
            return None
        # Stopped, not merely driving nothing: the planner's goal of the task this one interrupted is
        # cancelled, and the base told zero.
        return self.hold(
            f"waiting for {self.peer} to back out of the way"
            if self.meeting is Meeting.HEAD_ON_PRIORITY
            else f"giving way to {self.peer}"
        )
