"""One Zenoh subscriber per key expression and session, however many of the process's subscriptions read it.

zenoh-python runs a Python subscriber's callback on a thread of its own, one thread per subscriber: every
sample wakes that thread, which then waits for the interpreter lock. A composed robot's services each
subscribe to the robot's clock, odometry, scan, sonar, pose and static transforms, so one clock tick woke
four threads and one odometry sample three, each to find the same bytes (:class:`SharedDecodes
<shared.endpoints.SharedDecodes>` already decodes them once). Here the subscriptions of one session on one
key expression share one Zenoh subscriber: its thread hands each sample to every member in the order they
subscribed, as rclcpp's intra-process manager hands one message to each of its subscriptions.

Each member still keeps its own queue, executor and counters; only the thread and the subscriber are
shared. The members get a sample one after the other: a member whose node is idle runs its callback at
once on this thread (:meth:`Executor.try_run_now <shared.executor.Executor.try_run_now>`), so the next
member's delivery waits for that callback, as it would wait for its own subscription's earlier sample.
Callbacks on hot keys are short (they store the message), and the saving is one thread wake-up per member
and sample. A member that fails does not stop the sample reaching the others. Subscriptions with different
key expressions (an exact key and a wildcard that covers it) stay apart, as Zenoh declared them.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

import zenoh

log = logging.getLogger(__name__)

Deliver = Callable[[zenoh.Sample], None]


class _SharedSubscriber:
    """The Zenoh subscriber of one key expression on one session, and the members it feeds."""

    def __init__(self, session: zenoh.Session, key_expr: str) -> None:
        #: Replaced, never changed in place: Zenoh's thread reads it without the hub's lock.
        self.members: tuple[Deliver, ...] = ()
        self.subscriber: Any = session.declare_subscriber(key_expr, self._on_sample)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        for deliver in self.members:
            try:
                deliver(sample)
            except Exception:  # a bug in one member: the others still get the sample
                log.exception("a subscription failed on a sample of %s", sample.key_expr)


class SubscriptionHandle:
    """A member's place on a shared subscriber; :meth:`undeclare` leaves it (the last member undeclares it)."""

    def __init__(self, hub: SubscriberHub, session: zenoh.Session, key_expr: str, deliver: Deliver) -> None:
        self._hub = hub
        self._session = session
        self.key_expr = key_expr
        self._deliver = deliver
        self._declared = True

    def undeclare(self) -> None:
        if self._declared:
            self._declared = False
            self._hub._leave(self._session, self.key_expr, self._deliver)


class SubscriberHub:
    """The shared subscribers of this process, by session and key expression (module doc)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        #: ``id(session)`` -> (the session, its shared subscribers by key expression). The session is held so
        #: that its id is not reused while an entry names it.
        self._sessions: dict[int, tuple[zenoh.Session, dict[str, _SharedSubscriber]]] = {}

    def subscribe(self, session: zenoh.Session, key_expr: str, deliver: Deliver) -> SubscriptionHandle:
        """Have ``deliver(sample)`` called for every sample on ``key_expr``, on the key's shared subscriber."""
        with self._lock:
            self._forget_closed_sessions()
            _session, shared = self._sessions.setdefault(id(session), (session, {}))
            entry = shared.get(key_expr)
            if entry is None:
                entry = shared[key_expr] = _SharedSubscriber(session, key_expr)
            entry.members = (*entry.members, deliver)
        return SubscriptionHandle(self, session, key_expr, deliver)

    def subscriber_count(self, session: zenoh.Session) -> int:
        """How many Zenoh subscribers the hub holds on ``session`` (for tests and tools)."""
        with self._lock:
            found = self._sessions.get(id(session))
            return 0 if found is None else len(found[1])

    def _leave(self, session: zenoh.Session, key_expr: str, deliver: Deliver) -> None:
        with self._lock:
            found = self._sessions.get(id(session))
            entry = None if found is None else found[1].get(key_expr)
            if entry is None:
                return
            members = list(entry.members)
            if deliver in members:
                members.remove(deliver)
            entry.members = tuple(members)
            if members:
                return
            assert found is not None
            del found[1][key_expr]
            if not found[1]:
                del self._sessions[id(session)]
        try:
            entry.subscriber.undeclare()
        except zenoh.ZError:  # the session is closing or closed: the subscriber went with it
            pass

    def _forget_closed_sessions(self) -> None:
        """Drop the entries of sessions closed without their subscriptions undeclared (the caller holds the lock)."""
        for key in [k for k, (session, _) in self._sessions.items() if session.is_closed()]:
            del self._sessions[key]


#: This process's shared subscribers (every node of a composed process shares them).
SUBSCRIBER_HUB = SubscriberHub()
