"""Dock reservations for robots sharing a room: one robot per dock, leases, and a queue served by need.

A robot that needs charge asks for a dock before it drives to one. The book grants the dock it names if
that one is free, else the free dock nearest it by planned path length, and records the claim; the claim
is a lease the robot keeps alive while it is alive (its liveliness, or a renewed request) and gives back
when it undocks. So two robots never head for, or stand in, the same dock: a dock has at most one claim.

When every dock is claimed, the robot joins a queue served lowest battery first (then by name, so the
order never depends on arrival timing), and waits. A robot whose battery is critical may ask a robot that
is charged enough to leave its dock (``leave_requests``); the dock goes to the queue's head when it is
released.

A robot that vanishes (killed, partitioned) keeps its claim for ``lease_s`` after it was last heard from,
so a restart within that time finds its dock still its own; after that the dock is free again.

Pure: no bus, no clock. The fleet node feeds it requests and the time, and publishes its snapshot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass(frozen=True, slots=True)
class Claim:
    """A robot's reservation of a dock: granted at ``since_s``, alive while heard from within the lease."""

    robot: str
    dock_id: str
    since_s: float
    heard_s: float


@dataclass(frozen=True, slots=True)
class Waiting:
    """A robot in the queue for a dock, with the battery it last reported (0..1), and the holding spot
    (an index into the room's holding poses) it waits at, if the room has one free for it."""

    robot: str
    battery: float
    since_s: float
    heard_s: float = -math.inf
    spot: int | None = None


@dataclass(frozen=True, slots=True)
class Decision:
    """The book's answer to a request: a dock (``dock_id``), or a place in the queue (1 = next)."""

    dock_id: str | None
    queue_position: int = 0
    reason: str = ""
    #: Where a queued robot waits: an index into the room's holding poses (None: where it stands).
    holding_spot: int | None = None

    @property
    def granted(self) -> bool:
        return self.dock_id is not None


@dataclass
class DockBook:
    """Every dock's claim, and the queue, for one room."""

    dock_ids: tuple[str, ...]
    #: A claim whose robot has not been heard from for this long lapses.
    lease_s: float = 10.0
    #: At or below this charge a waiting robot may ask a charged one to leave its dock.
    critical_battery: float = 0.10
    #: ... a robot charged to at least this may be asked.
    charged_enough: float = 0.60
    #: How many holding poses the room has: each queued robot gets one of its own while any is free.
    holding_spots: int = 0
    claims: dict[str, Claim] = field(default_factory=dict)  # by dock id
    queue: dict[str, Waiting] = field(default_factory=dict)  # by robot
    #: Batteries last reported by claim holders (to know who is charged enough to leave).
    batteries: dict[str, float] = field(default_factory=dict)
    #: Robots asked to leave their dock for a critical one: holder -> the robot waiting for it.
    leave_requests: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if len(set(self.dock_ids)) != len(self.dock_ids) or not all(self.dock_ids):
            raise ValueError(f"dock ids must be distinct and non-empty, got {list(self.dock_ids)}")
        if not (math.isfinite(self.lease_s) and self.lease_s > 0):
            raise ValueError(f"lease_s must be a positive number of seconds, got {self.lease_s}")
        if not (0.0 <= self.critical_battery < self.charged_enough <= 1.0):
            raise ValueError("need 0 <= critical_battery < charged_enough <= 1")
        if self.holding_spots < 0:
            raise ValueError(f"holding_spots must be >= 0, got {self.holding_spots}")

    # --- questions ----------------------------------------------------------------------------------

    def holding(self, robot: str) -> str | None:
        """The dock ``robot`` holds, if any."""
        for dock_id, claim in self.claims.items():
            if claim.robot == robot:
                return dock_id
        return None

    def free_docks(self) -> list[str]:
        return [d for d in self.dock_ids if d not in self.claims]

    def queue_order(self) -> list[Waiting]:
        """The queue as it is served: lowest battery first, then by name."""
        return sorted(self.queue.values(), key=lambda w: (w.battery, w.robot))

    # --- changes ------------------------------------------------------------------------------------

    def request(
        self,
        robot: str,
        battery: float,
        now_s: float,
        wanted: str | None = None,
        path_lengths_m: dict[str, float] | None = None,
    ) -> Decision:
        """``robot`` (at charge ``battery``) asks for a dock: ``wanted`` by name, or the nearest free one by
        ``path_lengths_m`` (dock id -> planned path length; a dock missing or infinite there is out of
        reach). Asking again renews what it holds, or its place in the queue."""
        if not robot:
            raise ValueError("a request needs the robot's name")
        if wanted is not None and wanted not in self.dock_ids:
            return Decision(None, reason=f"no dock {wanted!r} (docks: {list(self.dock_ids)})")
        held = self.holding(robot)
        if held is not None:
            self.claims[held] = Claim(robot, held, self.claims[held].since_s, now_s)
            self.batteries[robot] = battery
            return Decision(held, reason="already yours")
        reachable = self._reachable(path_lengths_m)
        free = [d for d in self.free_docks() if d in reachable]
        waiting = self.queue_order()
        ahead = [w for w in waiting if w.robot != robot and (w.battery, w.robot) < (battery, robot)]
        if free and not ahead:
            if wanted is not None and wanted in free:
                choice = wanted
            else:
                choice = min(free, key=lambda d: (reachable[d], d))
            self.queue.pop(robot, None)
            self.claims[choice] = Claim(robot, choice, now_s, now_s)
            self.batteries[robot] = battery
            return Decision(choice, reason="granted")
        previous = self.queue.get(robot)
        spot = previous.spot if previous is not None and previous.spot is not None else self._free_spot()
        self.queue[robot] = Waiting(robot, battery, previous.since_s if previous else now_s, now_s, spot)
        position = [w.robot for w in self.queue_order()].index(robot) + 1
        reason = "every dock is taken" if not free else f"{len(ahead)} robot(s) with less charge go first"
        if battery <= self.critical_battery:
            self._ask_someone_to_leave(robot)
        return Decision(None, queue_position=position, reason=reason, holding_spot=spot)

    def heard_from(self, robot: str, now_s: float) -> None:
        """``robot`` is alive (its liveliness token, any message): its claim's lease runs from now."""
        held = self.holding(robot)
        if held is not None:
            claim = self.claims[held]
            self.claims[held] = Claim(robot, held, claim.since_s, max(claim.heard_s, now_s))
        waiting = self.queue.get(robot)
        if waiting is not None:
            self.queue[robot] = Waiting(
                robot, waiting.battery, waiting.since_s, max(waiting.heard_s, now_s), waiting.spot
            )

    def release(self, robot: str) -> str | None:
        """``robot`` gives its dock back (it undocked, or gave up); the dock it held, if any."""
        held = self.holding(robot)
        if held is not None:
            del self.claims[held]
        self.queue.pop(robot, None)
        self.batteries.pop(robot, None)
        self.leave_requests.pop(robot, None)
        return held

    def expire(self, now_s: float) -> list[Claim]:
        """Claims whose robot has not been heard from within ``lease_s``: ended, and returned. A queued
        robot not heard from for as long leaves the queue too (a dead robot must not hold up the living)."""
        lapsed = [c for c in self.claims.values() if now_s - c.heard_s > self.lease_s]
        for claim in lapsed:
            self.release(claim.robot)
        for waiting in [w for w in self.queue.values() if now_s - w.heard_s > self.lease_s]:
            self.release(waiting.robot)
        return lapsed

    def _free_spot(self) -> int | None:
        taken = {w.spot for w in self.queue.values()}
        return next((i for i in range(self.holding_spots) if i not in taken), None)

    def _reachable(self, path_lengths_m: dict[str, float] | None) -> dict[str, float]:
        if path_lengths_m is None:
            return dict.fromkeys(self.dock_ids, 0.0)
        return {
            d: float(v)
            for d, v in path_lengths_m.items()
            if d in self.dock_ids and math.isfinite(v) and v >= 0
        }

    def _ask_someone_to_leave(self, needy: str) -> None:
        if needy in self.leave_requests.values():
            return
        candidates = [
            (self.batteries.get(c.robot, 0.0), c.robot)
            for c in self.claims.values()
            if self.batteries.get(c.robot, 0.0) >= self.charged_enough and c.robot not in self.leave_requests
        ]
        if candidates:
            _, holder = max(candidates)
            self.leave_requests[holder] = needy
