"""Watches a fleet from the outside, on the bus, and measures it on ground truth.

Per robot: the distance it drove (ground truth, teleports left out), how often it docked (charging
began with its contacts mated), its lowest charge, how long it waited for a dock (sim time in
``WAITING_FOR_DOCK``), its collisions. For the room: collisions between robots (each robot reports one
contact; the pair is counted once) and with the world, and reservation conflicts: a robot whose contacts
mate with a dock the fleet's book does not give it, or two robots mated with one dock at once.

Zenoh callbacks only decode and update under a lock; reading takes a copy.
"""

from __future__ import annotations

import math
import threading
from array import array
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import zenoh

from shared import topics
from shared.interfaces.fleet import FleetDocks
from shared.messages import BatteryState, Clock, CollisionEvent, DockContact, PoseStamped, String
from shared.names import topic_key
from shared.schema import Message, MessageError

#: docking/state while a robot waits for a dock, and while it gives way to another robot.
WAITING_STATE = "WAITING_FOR_DOCK"
GIVING_WAY_STATE = "GIVING_WAY"
#: Ground truth that jumps further than this between samples was a teleport, not a drive.
TELEPORT_JUMP_M = 0.3
#: Track points for the picture are kept this far apart (at first: see :data:`TRACK_POINTS_MAX`).
TRACK_STEP_M = 0.1
#: A track longer than this drops every other point and doubles its step, so a run of any length keeps a
#: bounded picture (about half an hour of patrolling at the first step; 64 KiB a robot).
TRACK_POINTS_MAX = 4096
#: Two robots' reports of one contact between them are this close in sim time.
PAIR_WINDOW_S = 1.0
_CHARGING = (BatteryState.POWER_SUPPLY_STATUS_CHARGING, BatteryState.POWER_SUPPLY_STATUS_FULL)


class Track:
    """A robot's ground-truth track: points at least :attr:`step` metres apart, in order, at most
    :data:`TRACK_POINTS_MAX` of them.

    Kept as two arrays of doubles, 16 bytes a point, several times smaller than a list of ``(x, y)`` tuples,
    each allocated whole when the track is made (64 KiB a robot) and filled in place: over a long fleet run
    the tracks were most of what zendock's own process grew by, first as they filled, then as they were
    copied and thinned. Past the cap the track thins itself in place (every other point, twice the step), so
    it takes the same memory however long the run. Only the first ``len(track)`` items of :attr:`xs` and
    :attr:`ys` are points; iterate the track to read them."""

    __slots__ = ("_count", "step", "xs", "ys")

    def __init__(
        self,
        points: Iterable[tuple[float, float]] = (),
        step: float = TRACK_STEP_M,
        *,
        capacity: int = TRACK_POINTS_MAX,
    ) -> None:
        self.xs = array("d", bytes(8 * capacity))
        self.ys = array("d", bytes(8 * capacity))
        self._count = 0
        self.step = step
        for x, y in points:
            self.add(x, y)

    def add(self, x: float, y: float) -> None:
        """Append a point as it is, thinning the track first when it is full."""
        if self._count == TRACK_POINTS_MAX:
            self._thin()
        self.xs[self._count] = x
        self.ys[self._count] = y
        self._count += 1

    def _thin(self) -> None:
        """Keep every other point, the first included, in place, and double the step."""
        kept = (self._count + 1) // 2
        self.xs[:kept] = self.xs[: self._count : 2]
        self.ys[:kept] = self.ys[: self._count : 2]
        self._count = kept
        self.step *= 2.0

    @classmethod
    def without_points(cls, step: float = TRACK_STEP_M) -> Track:
        """An empty track that takes no memory, for a snapshot without tracks; it can hold no point."""
        return cls(step=step, capacity=0)

    def follow(self, x: float, y: float) -> None:
        """Append the point if it is at least a step from the last one (or is the first)."""
        if not self._count or math.dist(self.last(), (x, y)) >= self.step:
            self.add(x, y)

    def last(self) -> tuple[float, float]:
        """The latest point (``IndexError`` when there is none)."""
        if not self._count:
            raise IndexError("the track has no point yet")
        return self.xs[self._count - 1], self.ys[self._count - 1]

    def copy(self) -> Track:
        twin = Track(step=self.step)
        twin.xs[: self._count] = self.xs[: self._count]
        twin.ys[: self._count] = self.ys[: self._count]
        twin._count = self._count
        return twin

    def __len__(self) -> int:
        return self._count

    def __iter__(self) -> Iterator[tuple[float, float]]:
        return zip(self.xs[: self._count], self.ys[: self._count], strict=True)


@dataclass
class RobotTally:
    name: str
    distance_m: float = 0.0
    dockings: int = 0
    min_battery: float = math.inf
    battery: float = math.nan
    wait_s: float = 0.0
    collisions: int = 0
    collision_kinds: dict[str, int] = field(default_factory=dict)
    state: str = ""
    charging: bool = False
    track: Track = field(default_factory=Track)
    #: The dock its contacts are mated with now ("" when none).
    mated_dock: str = ""
    last_pose: tuple[float, float] | None = None
    state_since_s: float = math.nan
    #: How long each time it gave way lasted (sim seconds), from the meeting until the way was clear.
    give_ways_s: list[float] = field(default_factory=list)


@dataclass
class Conflict:
    sim_s: float
    robot: str
    dock_id: str
    holder: str

    def describe(self) -> str:
        return (
            f"{self.sim_s:.1f} s: {self.robot} mated with dock {self.dock_id} held by "
            f"{self.holder or 'nobody'}"
        )


class FleetMonitor:
    """Subscribes to every robot's keys and the fleet's on ``session``."""

    def __init__(self, session: zenoh.Session, robots: list[str], namespace: str = "") -> None:
        self._lock = threading.Lock()
        self.robots = {name: RobotTally(name) for name in robots}
        self.conflicts: list[Conflict] = []
        #: (sim time, x, y, robot, other) of robot-robot contacts, one per pair.
        self.robot_contacts: list[tuple[float, float, float, str, str]] = []
        self.sim_s = math.nan
        self._holders: dict[str, str] = {}
        self._fleet_docks_seen = False
        self._namespace = namespace
        key = lambda robot, name: topic_key(topic_key(namespace, robot) if namespace else robot, name)  # noqa: E731
        subs: list[Any] = []
        for robot in robots:
            subs += [
                session.declare_subscriber(
                    key(robot, topics.GROUND_TRUTH_POSE), self._decoder(PoseStamped, self._on_truth, robot)
                ),
                session.declare_subscriber(
                    key(robot, topics.BATTERY_STATUS), self._decoder(BatteryState, self._on_battery, robot)
                ),
                session.declare_subscriber(
                    key(robot, topics.DOCK_CONTACT), self._decoder(DockContact, self._on_contact, robot)
                ),
                session.declare_subscriber(
                    key(robot, topics.COLLISIONS), self._decoder(CollisionEvent, self._on_collision, robot)
                ),
                session.declare_subscriber(
                    key(robot, "docking/state"), self._decoder(String, self._on_state, robot)
                ),
            ]
        subs.append(
            session.declare_subscriber(key(robots[0], topics.CLOCK), self._decoder(Clock, self._on_clock, ""))
        )
        fleet_key = topic_key(namespace, topics.FLEET_DOCKS)
        subs.append(session.declare_subscriber(fleet_key, self._decoder(FleetDocks, self._on_docks, "")))
        self._subscribers = subs

    @staticmethod
    def _decoder(msg_type: type[Message], handler: Callable[[str, Any], None], robot: str):
        def on_sample(sample: zenoh.Sample) -> None:
            try:
                msg = msg_type.decode(sample.payload.to_bytes())
            except MessageError:
                return
            handler(robot, msg)

        return on_sample

    # --- callbacks (Zenoh threads) ------------------------------------------------------------------

    def _on_clock(self, _robot: str, msg: Clock) -> None:
        now = msg.clock.to_sec()
        with self._lock:
            previous = self.sim_s
            self.sim_s = now
            if math.isfinite(previous) and 0.0 < now - previous < 5.0:
                for tally in self.robots.values():
                    if tally.state == WAITING_STATE:
                        tally.wait_s += now - previous

    def _on_truth(self, robot: str, msg: PoseStamped) -> None:
        p = msg.pose.position
        with self._lock:
            tally = self.robots[robot]
            here = (p.x, p.y)
            if tally.last_pose is not None:
                step = math.dist(tally.last_pose, here)
                if step < TELEPORT_JUMP_M:
                    tally.distance_m += step
            tally.last_pose = here
            tally.track.follow(p.x, p.y)

    def _on_battery(self, robot: str, msg: BatteryState) -> None:
        with self._lock:
            tally = self.robots[robot]
            if math.isfinite(msg.percentage):
                tally.battery = msg.percentage
                tally.min_battery = min(tally.min_battery, msg.percentage)
            charging = msg.power_supply_status in _CHARGING
            if charging and not tally.charging:
                tally.dockings += 1  # the battery charges only on mated contacts
            tally.charging = charging

    def _on_contact(self, robot: str, msg: DockContact) -> None:
        with self._lock:
            tally = self.robots[robot]
            dock = msg.dock_id if msg.mated else ""
            if dock and dock != tally.mated_dock:
                holder = self._holders.get(dock, "")
                others = [r.name for r in self.robots.values() if r.name != robot and r.mated_dock == dock]
                if others:
                    self.conflicts.append(Conflict(self.sim_s, robot, dock, others[0]))
                elif self._fleet_docks_seen and holder != self._robot_key(robot):
                    self.conflicts.append(Conflict(self.sim_s, robot, dock, holder))
            tally.mated_dock = dock

    def _on_collision(self, robot: str, msg: CollisionEvent) -> None:
        t = msg.header.stamp.to_sec()
        with self._lock:
            tally = self.robots[robot]
            tally.collisions += 1
            tally.collision_kinds[msg.kind] = tally.collision_kinds.get(msg.kind, 0) + 1
            if msg.kind == "robot":
                pair = sorted((robot, msg.other_robot))
                seen = any(
                    sorted((a, b)) == pair and abs(t - s) < PAIR_WINDOW_S
                    for s, _, _, a, b in self.robot_contacts
                )
                if not seen:
                    self.robot_contacts.append((t, msg.x, msg.y, robot, msg.other_robot))

    def _on_state(self, robot: str, msg: String) -> None:
        with self._lock:
            tally = self.robots[robot]
            if msg.data == tally.state:
                return
            if msg.data == GIVING_WAY_STATE:
                tally.state_since_s = self.sim_s
            elif tally.state == GIVING_WAY_STATE and math.isfinite(tally.state_since_s):
                tally.give_ways_s.append(self.sim_s - tally.state_since_s)
            tally.state = msg.data

    def _on_docks(self, _robot: str, msg: FleetDocks) -> None:
        with self._lock:
            self._fleet_docks_seen = True
            self._holders = {d.dock_id: d.robot for d in msg.docks}

    def _robot_key(self, robot: str) -> str:
        return topic_key(self._namespace, robot) if self._namespace else robot

    # --- reading --------------------------------------------------------------------------------------

    def snapshot(
        self, *, tracks: bool = True
    ) -> tuple[float, list[RobotTally], list[Conflict], list[tuple[float, float, float, str, str]]]:
        """A copy of everything heard so far. ``tracks=False`` leaves each robot's track empty: progress
        lines, every few seconds, need no track, and copying every track each time cost memory that the
        allocator did not give back."""
        with self._lock:
            robots = [
                RobotTally(
                    **{
                        **t.__dict__,
                        "track": t.track.copy() if tracks else Track.without_points(t.track.step),
                        "collision_kinds": dict(t.collision_kinds),
                        "give_ways_s": list(t.give_ways_s),
                    }
                )
                for t in self.robots.values()
            ]
            return self.sim_s, robots, list(self.conflicts), list(self.robot_contacts)

    def sim_time(self) -> float:
        """The simulator's clock as last heard (NaN before the first tick): a look that copies nothing."""
        with self._lock:
            return self.sim_s

    def close(self) -> None:
        for sub in self._subscribers:
            sub.undeclare()
        self._subscribers.clear()
