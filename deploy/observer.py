"""Watches one robot's docking run from the outside, on the bus, and measures it on ground truth.

The observer never talks to a service's internals: it listens to the keys any tool could (battery,
the simulator's ground truth, collisions, the plan, the ultrasonic range, the navigation action's
feedback, whose recovery count says where recoveries happened) and derives the run's numbers:
when the battery crossed the low threshold (the trigger), when charging began, how far the robot
drove, and the lateral and yaw error of its contacts at the moment charging began.

Zenoh callbacks only decode and append under a lock; all arithmetic happens in the caller's thread.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from typing import Any

import zenoh

from shared import topics
from shared.action import action_key
from shared.contracts.services import DOCKING_STATE
from shared.geometry import Pose2D
from shared.interfaces.navigation import NAVIGATE_TO_POSE
from shared.messages import BatteryState, Clock, CollisionEvent, DockContact, Path, PoseStamped, Range, String
from shared.names import topic_key
from shared.schema import Message, MessageError

#: The ultrasonic sensor's mount on base_link (the simulator's default), for placing sonar hits.
ULTRASONIC_MOUNT = Pose2D(0.20, 0.0, 0.0)


#: The battery charges on a mated dock_contact at most this old (its ``dock_contact_timeout_s``): the mating
#: that started charging is no older, and a mated reading from before the robot was last put down is.
MATED_BEFORE_CHARGING_S = 1.0
#: ... and the mated reading may arrive stamped up to this long after it (publishers' order is not kept).
MATED_AFTER_CHARGING_S = 0.5

#: The arrival speed is the ground-truth speed averaged over this long before the contacts mated (the last
#: three samples at 20 Hz): a robot still braking there reads a little faster than it touched.
ARRIVAL_SPEED_WINDOW_S = 0.1

#: The plate's contact speed limit: a robot that meets its dock faster has not docked, charging or not (a
#: real base bounces off the plate or breaks its contacts). The approach meets it at 0.08 m/s.
ARRIVAL_SPEED_LIMIT_MPS = 0.10

#: Ground truth that moves further than this between two samples was teleported: at 20 Hz a drive at
#: 0.5 m/s moves 2.5 cm a sample, so even a dozen lost samples stay under it.
TELEPORT_JUMP_M = 0.3


@dataclass(frozen=True)
class DockingOutcome:
    """One docking's figures as every report gives them (the demo's and each trial's), from a record."""

    #: Charging with the contacts mated, having met the plate no faster than its contact speed limit.
    docked: bool
    charging: bool
    #: Charging after meeting the plate faster than :data:`ARRIVAL_SPEED_LIMIT_MPS`: not docked.
    too_fast: bool
    #: Sim seconds from the low-battery trigger to charging (NaN: it never charged, or never triggered).
    dock_time_s: float
    #: How far off the dock's axis and heading the contacts mated (absolute; NaN without a contact).
    lateral_error_m: float
    yaw_error_rad: float
    collisions: int
    #: Ground-truth distance driven since the trigger.
    path_length_m: float
    trigger_s: float


@dataclass
class RunRecord:
    """What the observer saw, as plain data (sim-time seconds)."""

    trigger_s: float | None = None
    charging_s: float | None = None
    contact_at_charging: DockContact | None = None
    collisions: int = 0
    collision_kinds: list[str] = field(default_factory=list)
    #: Where each collision happened (x, y), for the picture.
    collision_points: list[tuple[float, float]] = field(default_factory=list)
    driven: list[tuple[float, float, float, float]] = field(default_factory=list)  # (t, x, y, yaw)
    plans: list[list[tuple[float, float]]] = field(default_factory=list)
    #: Each sonar echo as the sensor heard it: (sensor_x, sensor_y, sensor_yaw, range_m, field_of_view_rad),
    #: the sensor's ground-truth pose at the reading's stamp (the echo came from somewhere in the cone).
    sonar_echoes: list[tuple[float, float, float, float, float]] = field(default_factory=list)
    battery: list[tuple[float, float]] = field(default_factory=list)  # (t, percentage)
    sim_time_s: float = 0.0
    #: Whether the latest battery message said CHARGING or FULL.
    last_charging: bool = False
    #: Where the robot stood (x, y) each time navigation began a recovery, for the picture.
    recovery_points: list[tuple[float, float]] = field(default_factory=list)
    #: Each change of the docking service's ``docking/state`` (sim time it arrived, the state's name).
    phases: list[tuple[float, str]] = field(default_factory=list)
    #: When the contacts mated in the mating that started charging (the first of its run of mated readings).
    mated_s: float | None = None

    @property
    def charging(self) -> bool:
        return self.charging_s is not None

    def outcome(self) -> DockingOutcome:
        """The docking's figures (the one mapping from a record to what reports say of it)."""
        contact = self.contact_at_charging
        trigger = self.trigger_s if self.trigger_s is not None else math.nan
        mated = bool(self.charging and contact is not None and contact.mated)
        too_fast = mated and self.arrival_speed_mps > ARRIVAL_SPEED_LIMIT_MPS  # False for NaN (no track)
        return DockingOutcome(
            docked=mated and not too_fast,
            charging=self.charging,
            too_fast=too_fast,
            dock_time_s=(self.charging_s - trigger) if self.charging_s is not None else math.nan,
            lateral_error_m=abs(contact.lateral_error_m) if contact is not None else math.nan,
            yaw_error_rad=abs(contact.yaw_error_rad) if contact is not None else math.nan,
            collisions=self.collisions,
            path_length_m=self.driven_length_m(since_s=self.trigger_s),
            trigger_s=trigger,
        )

    def driven_length_m(self, since_s: float | None = None) -> float:
        points = [(x, y) for t, x, y, _ in self.driven if since_s is None or t >= since_s]
        return sum(math.dist(a, b) for a, b in zip(points, points[1:]))

    def driven_since_placed(self) -> list[tuple[float, float]]:
        """The ground-truth track (x, y) since the robot was last put down (``--start``), for the picture."""
        return [(x, y) for _, x, y in self.timed_track_since_placed()]

    def timed_track_since_placed(self) -> list[tuple[float, float, float]]:
        """:meth:`driven_since_placed` with each point's sim time: ``(t_s, x, y)``."""
        start = 0
        for i in range(1, len(self.driven)):
            if math.dist(self.driven[i - 1][1:3], self.driven[i][1:3]) > TELEPORT_JUMP_M:
                start = i
        return [(t, x, y) for t, x, y, _ in self.driven[start:]]

    def phase_durations(self) -> dict[str, float]:
        """Sim seconds from the trigger to charging spent in each docking state (``docking/state``).

        ``TRIGGER`` is the time from the battery's crossing to the docking service's first state change
        after it, leaving IDLE (hearing the battery, starting the run); a state entered twice (a retry)
        counts once, summed.
        Empty unless the run both triggered and charged.
        """
        durations: dict[str, float] = {}
        for name, since, until in self._phase_windows():
            durations[name] = durations.get(name, 0.0) + (until - since)
        return {name: round(seconds, 3) for name, seconds in durations.items()}

    def phase_lengths_m(self) -> dict[str, float]:
        """Ground-truth metres driven in each docking state from the trigger to charging (the states of
        :meth:`phase_durations`; a step that spans a change of state counts in neither)."""
        lengths: dict[str, float] = {}
        for name, since, until in self._phase_windows():
            points = [(x, y) for t, x, y, _ in self.driven if since <= t <= until]
            metres = sum(math.dist(a, b) for a, b in zip(points, points[1:]))
            lengths[name] = lengths.get(name, 0.0) + metres
        return {name: round(metres, 4) for name, metres in lengths.items()}

    def _phase_windows(self) -> list[tuple[str, float, float]]:
        """``(state, from, until)`` in sim seconds, from the trigger to charging (empty unless both)."""
        if self.trigger_s is None or self.charging_s is None:
            return []
        begin, end = self.trigger_s, self.charging_s
        windows: list[tuple[str, float, float]] = []
        current, since = "TRIGGER", begin
        for t, name in self.phases:
            if t <= begin:
                current = (
                    "TRIGGER" if name == "IDLE" else name
                )  # what the trigger found: a run already under way?
                continue
            if t >= end:
                break
            windows.append((current, since, t))
            current, since = name, t
        windows.append((current, since, end))
        return windows

    def speed_at(self, t_s: float, window_s: float = ARRIVAL_SPEED_WINDOW_S) -> float:
        """The ground-truth speed (m/s) over the ``window_s`` before ``t_s``: NaN without track there."""
        samples = [(t, x, y) for t, x, y, _ in self.driven if t_s - window_s - 1e-9 <= t <= t_s + 1e-9]
        if len(samples) < 2 or samples[-1][0] <= samples[0][0]:
            return math.nan
        length = sum(math.dist(a[1:], b[1:]) for a, b in zip(samples, samples[1:]))
        return length / (samples[-1][0] - samples[0][0])

    @property
    def arrival_speed_mps(self) -> float:
        """How fast the robot met the dock: its speed as the contacts mated (NaN if they never did)."""
        return self.speed_at(self.mated_s) if self.mated_s is not None else math.nan

    def pose_at(self, t_s: float) -> Pose2D | None:
        """The ground-truth pose at (or just before) ``t_s``."""
        best = None
        for t, x, y, yaw in self.driven:
            if t > t_s:
                break
            best = Pose2D(x, y, yaw)
        return best if best is not None else (Pose2D(*self.driven[0][1:]) if self.driven else None)


class RunObserver:
    """Subscribes to one robot's keys on ``session`` (namespace ``namespace``)."""

    def __init__(self, session: zenoh.Session, namespace: str = "", low_threshold: float = 0.25) -> None:
        self.namespace = namespace
        self.low_threshold = low_threshold
        self._lock = threading.Lock()
        self._record = RunRecord()
        self._contacts: list[DockContact] = []
        self._truth: Pose2D | None = None
        self._armed = False
        self._changed = threading.Condition(self._lock)
        key = lambda name: topic_key(namespace, name)  # noqa: E731
        self._subscribers = [
            session.declare_subscriber(key(topics.CLOCK), self._decoder(Clock, self._on_clock)),
            session.declare_subscriber(
                key(topics.BATTERY_STATUS), self._decoder(BatteryState, self._on_battery)
            ),
            session.declare_subscriber(
                key(topics.DOCK_CONTACT), self._decoder(DockContact, self._on_contact)
            ),
            session.declare_subscriber(
                key(topics.COLLISIONS), self._decoder(CollisionEvent, self._on_collision)
            ),
            session.declare_subscriber(
                key(topics.GROUND_TRUTH_POSE), self._decoder(PoseStamped, self._on_truth)
            ),
            session.declare_subscriber(key(topics.PLAN), self._decoder(Path, self._on_plan)),
            session.declare_subscriber(key(topics.ULTRASONIC), self._decoder(Range, self._on_range)),
            session.declare_subscriber(key(DOCKING_STATE), self._decoder(String, self._on_docking_state)),
            session.declare_subscriber(
                key(action_key(topics.NAVIGATE_TO_POSE, "feedback")),
                self._decoder(NAVIGATE_TO_POSE.feedback_message, self._on_nav_feedback),
            ),
        ]
        #: Per navigation goal (its id's bytes), the recovery count its feedback last gave.
        self._recoveries_seen: dict[bytes, int] = {}

    @staticmethod
    def _decoder(msg_type: type[Message], handler: Any):
        def on_sample(sample: zenoh.Sample) -> None:
            try:
                msg = msg_type.decode(sample.payload.to_bytes())
            except MessageError:
                return  # a tool watching the bus ignores what it cannot read; services count it
            handler(msg)

        return on_sample

    def arm(self) -> None:
        """From now on, the first crossing below the threshold (or a reading already below it) is the trigger,
        and sonar hits are kept for the picture."""
        with self._lock:
            self._armed = True

    # --- callbacks (Zenoh threads) --------------------------------------------------------------------

    def _on_clock(self, msg: Clock) -> None:
        with self._lock:
            self._record.sim_time_s = msg.clock.to_sec()

    def _on_battery(self, msg: BatteryState) -> None:
        t = msg.header.stamp.to_sec()
        with self._changed:
            record = self._record
            record.battery.append((t, msg.percentage))
            if self._armed and record.trigger_s is None and msg.percentage < self.low_threshold:
                record.trigger_s = t  # crossed below, or was already below when armed
            charging = msg.power_supply_status in (
                BatteryState.POWER_SUPPLY_STATUS_CHARGING,
                BatteryState.POWER_SUPPLY_STATUS_FULL,
            )
            record.last_charging = charging
            if charging and record.trigger_s is not None and record.charging_s is None:
                record.charging_s = t
            self._changed.notify_all()

    def _contact_at(self, t_s: float) -> DockContact | None:
        """The contact state when charging began: the mating that started it (messages from different
        publishers arrive in any order, so the mated reading may come just after the battery's)."""
        mated = self._mated_near(t_s)
        if mated:
            before = [c for c in mated if c.header.stamp.to_sec() <= t_s + 1e-6]
            return before[-1] if before else mated[0]
        return self._contacts[-1] if self._contacts else None

    def _mated_near(self, t_s: float) -> list[DockContact]:
        """The mated readings that may have started charging at ``t_s``: the window both
        :meth:`_contact_at` and :meth:`settle` look in."""
        return [
            c
            for c in self._contacts
            if c.mated
            and t_s - MATED_BEFORE_CHARGING_S <= c.header.stamp.to_sec() <= t_s + MATED_AFTER_CHARGING_S
        ]

    def _on_contact(self, msg: DockContact) -> None:
        with self._changed:
            self._changed.notify_all()
            self._contacts.append(msg)
            if len(self._contacts) > 400 and self._record.charging_s is None:
                del self._contacts[:200]

    def _on_collision(self, msg: CollisionEvent) -> None:
        with self._changed:
            self._record.collisions += 1
            self._record.collision_kinds.append(msg.kind)
            self._record.collision_points.append((msg.x, msg.y))
            self._changed.notify_all()

    def _on_truth(self, msg: PoseStamped) -> None:
        pose = msg.pose.to_pose2d()
        with self._lock:
            self._truth = pose
            self._record.driven.append((msg.header.stamp.to_sec(), pose.x, pose.y, pose.yaw))

    def _on_plan(self, msg: Path) -> None:
        points = [(p.pose.position.x, p.pose.position.y) for p in msg.poses]
        if points:
            with self._lock:
                self._record.plans.append(points)
                if len(self._record.plans) > 50:
                    del self._record.plans[1:26]  # keep the first plan and the recent ones

    def _on_range(self, msg: Range) -> None:
        if not (math.isfinite(msg.range) and msg.min_range <= msg.range < msg.max_range):
            return
        with self._lock:
            if (
                self._truth is None or not self._armed
            ):  # before arm(): maybe still where --start moves it from
                return
            # Where the robot was when the sonar listened, not where it is now the message has arrived.
            sensor = self._truth_at(msg.header.stamp.to_sec()).compose(ULTRASONIC_MOUNT)
            echoes = self._record.sonar_echoes
            last = echoes[-1] if echoes else None
            if (
                last is None
                or math.dist(last[:2], (sensor.x, sensor.y)) > 0.02
                or abs(last[3] - msg.range) > 0.02
                or abs(last[2] - sensor.yaw) > 0.02
            ):
                echoes.append((sensor.x, sensor.y, sensor.yaw, msg.range, msg.field_of_view))

    def _on_docking_state(self, msg: String) -> None:
        with self._lock:
            if not self._armed:
                return
            phases = self._record.phases
            if not phases or phases[-1][1] != msg.data:
                phases.append((self._record.sim_time_s, msg.data))

    def _on_nav_feedback(self, msg: Any) -> None:
        count = msg.feedback.number_of_recoveries
        goal = bytes(msg.goal_id.uuid)
        with self._lock:
            seen = self._recoveries_seen.get(goal, 0)
            if count <= seen:
                return
            if len(self._recoveries_seen) > 100:
                self._recoveries_seen.clear()
            self._recoveries_seen[goal] = count
            if self._truth is None or not self._armed:
                return
            where = self._truth_at(msg.feedback.current_pose.header.stamp.to_sec())
            self._record.recovery_points.extend([(where.x, where.y)] * (count - seen))

    def _truth_at(self, stamp_s: float) -> Pose2D:
        """The ground-truth pose at (or just before) ``stamp_s`` among the recent samples (lock held)."""
        driven = self._record.driven
        for i in range(len(driven) - 1, max(-1, len(driven) - 200), -1):
            t, x, y, yaw = driven[i]
            if t <= stamp_s:
                return Pose2D(x, y, yaw)
        assert self._truth is not None
        return self._truth

    # --- reading ----------------------------------------------------------------------------------------

    def snapshot(self) -> RunRecord:
        with self._lock:
            r = self._record
            contact = self._contact_at(r.charging_s) if r.charging_s is not None else None
            return RunRecord(
                r.trigger_s,
                r.charging_s,
                contact,
                r.collisions,
                list(r.collision_kinds),
                list(r.collision_points),
                list(r.driven),
                [list(p) for p in r.plans],
                list(r.sonar_echoes),
                list(r.battery),
                r.sim_time_s,
                r.last_charging,
                list(r.recovery_points),
                list(r.phases),
                self._mating_began(contact) if contact is not None and contact.mated else None,
            )

    def _mating_began(self, contact: DockContact) -> float:
        """The stamp of the first mated reading in the unbroken run of them that ends with ``contact``."""
        ordered = sorted(self._contacts, key=lambda c: c.header.stamp.to_sec())
        end = contact.header.stamp.to_sec()
        began = end
        for reading in reversed(ordered):
            stamp = reading.header.stamp.to_sec()
            if stamp > end:
                continue
            if not reading.mated:
                break
            began = stamp
        return began

    def settle(self, timeout_s: float = 5.0) -> None:
        """After charging began, wait (briefly) for the simulator's contact readings of that moment: a mated
        one, or readings from half a second past it (the window :meth:`_contact_at` looks in). A reading
        just past the moment is not enough: on a busy machine the mated one may still be on its way."""

        def seen() -> bool:
            t = self._record.charging_s
            return (
                t is None
                or any(c.header.stamp.to_sec() >= t + MATED_AFTER_CHARGING_S for c in self._contacts)
                or bool(self._mated_near(t))
            )

        with self._changed:
            self._changed.wait_for(seen, timeout=timeout_s)

    def sim_time(self) -> float:
        with self._lock:
            return self._record.sim_time_s

    def wait(self, predicate: Any, timeout_s: float) -> bool:
        """Block until ``predicate(record)`` holds (checked on battery and collision events) or timeout."""
        with self._changed:
            return self._changed.wait_for(lambda: predicate(self._record), timeout=timeout_s)

    def close(self) -> None:
        for sub in self._subscribers:
            sub.undeclare()
        self._subscribers.clear()
