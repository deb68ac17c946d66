"""Subscriptions of one session on one key share one Zenoh subscriber (and its thread), and still each get
every sample, keep their own counters, and leave without taking the others' samples away."""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator
from typing import Any

import pytest
import zenoh

from shared.messages import Clock, Time, Twist
from shared.node import RELIABLE, Node
from shared.session import SessionSpec, open_session
from shared.subscriber_hub import SUBSCRIBER_HUB, SubscriberHub
from tests.support.processes import wait_until


@pytest.fixture
def session(router_endpoint: str) -> Iterator[zenoh.Session]:
    with open_session(SessionSpec(connect=(router_endpoint,))) as opened:
        yield opened


def _once_heard(bus: zenoh.Session, key: str) -> zenoh.Publisher:
    """A publisher on ``key`` that the bus already matches with a subscriber: a put made before the
    subscription reached the router would go nowhere."""
    publisher = bus.declare_publisher(key)

    def matched() -> bool:
        status: Any = publisher.matching_status  # a MatchingStatus (the stub says bool)
        return bool(status.matching)

    wait_until(matched, 5.0, f"no subscriber on {key} reached the bus")
    return publisher


def _thread_count() -> int:
    return len(os.listdir(f"/proc/{os.getpid()}/task"))


def test_nodes_on_one_session_share_a_subscriber_per_key(
    session: zenoh.Session, bus: zenoh.Session, namespace: str
) -> None:
    threads_before = _thread_count()
    nodes = [Node(f"n{i}", session, namespace, use_sim_time=True) for i in range(4)]
    got: list[list[float]] = [[] for _ in nodes]
    for node, seen in zip(nodes, got, strict=True):
        node.create_subscription(Twist, "cmd_vel", lambda m, seen=seen: seen.append(m.linear.x), RELIABLE)
    try:
        # four clock subscriptions and four cmd_vel subscriptions: two Zenoh subscribers, two threads
        assert SUBSCRIBER_HUB.subscriber_count(session) == 2
        assert _thread_count() - threads_before <= 2, "one callback thread per shared subscriber"
        spinners = [threading.Thread(target=n.spin, daemon=True) for n in nodes]
        for spinner in spinners:
            spinner.start()
        cmd_vel = _once_heard(bus, f"{namespace}/cmd_vel")
        for i in range(3):
            cmd_vel.put(Twist.planar(0.1 * (i + 1), 0.0).encode())
        _once_heard(bus, f"{namespace}/clock").put(Clock(Time.from_sec(2.5)).encode())
        wait_until(
            lambda: all(len(seen) == 3 for seen in got) and all(n.now() == 2.5 for n in nodes),
            5.0,
            lambda: f"samples so far {got}, clocks {[n.now() for n in nodes]}",
        )
        assert all(seen == pytest.approx([0.1, 0.2, 0.3]) for seen in got), got
        assert all(n.stats.received[f"{namespace}/cmd_vel"] == 3 for n in nodes), "each node counts its own"
    finally:
        for node in nodes:
            node.close()
    assert SUBSCRIBER_HUB.subscriber_count(session) == 0, "the last node to close undeclares the subscribers"


def test_a_member_that_leaves_takes_nothing_from_the_others(
    session: zenoh.Session, bus: zenoh.Session, namespace: str
) -> None:
    stays, leaves = Node("stays", session, namespace), Node("leaves", session, namespace)
    kept: list[float] = []
    gone: list[float] = []
    stays.create_subscription(Twist, "cmd_vel", lambda m: kept.append(m.linear.x), RELIABLE)
    sub = leaves.create_subscription(Twist, "cmd_vel", lambda m: gone.append(m.linear.x), RELIABLE)
    spinners = [threading.Thread(target=n.spin, daemon=True) for n in (stays, leaves)]
    for spinner in spinners:
        spinner.start()
    try:
        cmd_vel = _once_heard(bus, f"{namespace}/cmd_vel")
        cmd_vel.put(Twist.planar(1.0, 0.0).encode())
        wait_until(lambda: kept == [1.0] and gone == [1.0], 5.0, lambda: f"kept {kept}, gone {gone}")
        sub.undeclare()
        assert SUBSCRIBER_HUB.subscriber_count(session) == 1
        cmd_vel.put(Twist.planar(2.0, 0.0).encode())
        wait_until(lambda: kept == [1.0, 2.0], 5.0, lambda: f"kept {kept}")
        assert gone == [1.0], "the member that left gets no more samples"
    finally:
        stays.close()
        leaves.close()


def test_a_failing_member_does_not_stop_the_sample_reaching_the_next(
    session: zenoh.Session, bus: zenoh.Session, namespace: str
) -> None:
    hub = SubscriberHub()
    reached: list[bytes] = []

    def broken(_sample: zenoh.Sample) -> None:
        raise RuntimeError("a bug in one member")

    key = f"{namespace}/raw"
    handles = [
        hub.subscribe(session, key, broken),
        hub.subscribe(session, key, lambda s: reached.append(s.payload.to_bytes())),
    ]
    try:
        _once_heard(bus, key).put(b"x")
        wait_until(lambda: reached == [b"x"], 5.0, lambda: f"reached {reached}")
    finally:
        for handle in handles:
            handle.undeclare()
    assert hub.subscriber_count(session) == 0


def test_a_closed_session_is_forgotten(router_endpoint: str, session: zenoh.Session, namespace: str) -> None:
    hub = SubscriberHub()
    with open_session(SessionSpec(connect=(router_endpoint,))) as short_lived:
        hub.subscribe(short_lived, f"{namespace}/a", lambda _s: None)  # never undeclared
        assert hub.subscriber_count(short_lived) == 1
    handle = hub.subscribe(session, f"{namespace}/a", lambda _s: None)
    assert hub.subscriber_count(short_lived) == 0, "the closed session's entry went with the next subscribe"
    handle.undeclare()


def test_a_subscription_the_contract_refuses_leaves_the_shared_subscriber(
    session: zenoh.Session, namespace: str
) -> None:
    node = Node("strict", session, namespace)

    def refuse(kind: str, type_name: str, key: str) -> None:
        raise ValueError(f"{kind} {type_name} on {key} is not in the contract")

    node.endpoint_check = refuse
    try:
        with pytest.raises(ValueError, match="not in the contract"):
            node.create_subscription(Twist, "cmd_vel", lambda _m: None, RELIABLE)
        assert SUBSCRIBER_HUB.subscriber_count(session) == 0
    finally:
        node.close()
