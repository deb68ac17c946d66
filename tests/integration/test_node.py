"""The node runtime over a real router: typed pub/sub, rejection of bad input, timers, requests."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest
import zenoh

from shared.messages import Bool, Clock, Time, Twist
from shared.node import RELIABLE, Node, QoS, ServiceError, ServiceType, call_service, sequence_number
from shared.session import SessionSpec, open_session
from tests.support.bus import liveliness_keys
from tests.support.processes import wait_until

ECHO = ServiceType("zendock_msgs/srv/Echo", Twist, Twist)


@pytest.fixture
def node_pair(router_endpoint: str, namespace: str) -> Iterator[tuple[Node, Node]]:
    with (
        open_session(SessionSpec(connect=(router_endpoint,))) as s1,
        open_session(SessionSpec(connect=(router_endpoint,))) as s2,
    ):
        a, b = Node("talker", s1, namespace), Node("listener", s2, namespace, use_sim_time=True)
        spinner = threading.Thread(target=b.spin, daemon=True)
        spinner.start()
        yield a, b
        b.shutdown()
        spinner.join(5)
        a.close()
        b.close()


def _wait(event: threading.Event, what: str, timeout_s: float = 5.0) -> None:
    assert event.wait(timeout_s), f"timed out waiting for {what}"


def test_typed_pub_sub_and_rejection(node_pair: tuple[Node, Node], bus: zenoh.Session) -> None:
    talker, listener = node_pair
    got: list[Twist] = []
    done = threading.Event()

    def on_twist(msg: Twist) -> None:
        got.append(msg)
        if len(got) == 3:
            done.set()

    listener.create_subscription(Twist, "cmd_vel", on_twist, RELIABLE)
    pub = talker.create_publisher(Twist, "cmd_vel")
    token = f"/sub/{listener.namespace}/listener/geometry_msgs%msg%Twist/{listener.namespace}/cmd_vel"
    wait_until(
        lambda: any(k.endswith(token) for k in liveliness_keys(bus)),
        5.0,
        lambda: f"no token ending {token}: {liveliness_keys(bus)}",
    )
    for bad in (b"garbage", Bool(True).encode()):
        bus.put(talker.key("cmd_vel"), bad)
    for i in range(3):
        pub.publish(Twist.planar(0.1 * i, 0.0))
    _wait(done, "three twists")
    assert [m.linear.x for m in got] == pytest.approx([0.0, 0.1, 0.2])
    # the bad payloads come through another session: they may arrive after the good ones
    rejected = listener.stats.rejected
    wait_until(
        lambda: rejected.get(talker.key("cmd_vel"), 0) >= 2,
        5.0,
        lambda: f"rejections so far: {dict(rejected)}",
    )
    assert rejected[talker.key("cmd_vel")] == 2


def test_sequence_numbers_attached(node_pair: tuple[Node, Node], bus: zenoh.Session) -> None:
    talker, _ = node_pair
    seqs: list[int | None] = []
    done = threading.Event()
    sub = bus.declare_subscriber(
        talker.key("seq"),
        lambda s: (seqs.append(sequence_number(s.attachment)), len(seqs) == 3 and done.set()),
    )
    pub = talker.create_publisher(Bool, "seq")
    # the raw subscriber declares no token: wait until the publisher's route to it is up
    wait_until(pub.has_subscribers, 5.0, "the publisher never matched the subscriber")
    for _ in range(3):
        pub.publish(Bool(True))
    _wait(done, "three samples")
    sub.undeclare()
    assert seqs == [1, 2, 3]


def test_a_command_carries_the_control_tick_it_answers(node_pair: tuple[Node, Node]) -> None:
    """What the simulator's lockstep reads: the tick a command was computed on, or None when not said."""
    talker, listener = node_pair
    got: list[tuple[float, float | None]] = []
    done = threading.Event()

    def on_twist(msg: Twist, answered: float | None) -> None:
        got.append((msg.linear.x, answered))
        if len(got) == 2:
            done.set()

    sub = listener.create_subscription(Twist, "drive", on_twist, RELIABLE, with_answered=True)
    pub = talker.create_publisher(Twist, "drive")
    wait_until(pub.has_subscribers, 5.0, "the publisher never matched the subscriber")
    pub.publish(Twist.planar(0.3, 0.0), answers_s=12.35)
    pub.publish(Twist.planar(0.0, 0.0))
    _wait(done, "two twists")
    sub.undeclare()
    assert got == [(0.3, pytest.approx(12.35)), (0.0, None)]


def test_a_publisher_hears_of_subscribers_coming_and_going(node_pair: tuple[Node, Node]) -> None:
    talker, listener = node_pair
    changes: list[bool] = []
    pub = talker.create_publisher(Bool, "wanted")
    pub.on_matching_change(changes.append)
    sub = listener.create_subscription(Bool, "wanted", lambda _m: None, RELIABLE)
    wait_until(lambda: changes[-1:] == [True], 5.0, lambda: f"matching changes so far: {changes}")
    sub.undeclare()
    wait_until(lambda: changes[-1:] == [False], 5.0, lambda: f"matching changes so far: {changes}")
    assert not pub.has_subscribers()
    pub.undeclare()  # with its listener


def test_sim_time_timer_follows_clock(node_pair: tuple[Node, Node]) -> None:
    talker, listener = node_pair
    ticks: list[float] = []
    done = threading.Event()

    def tick() -> None:
        ticks.append(listener.now())
        if len(ticks) == 5:
            done.set()

    listener.create_timer(0.1, tick)
    clock = talker.create_publisher(Clock, "clock", QoS(depth=1))
    for i in range(200):
        clock.publish(Clock(Time.from_sec(i * 0.01)))
        if done.is_set():
            break
        done.wait(0.002)
    _wait(done, "five sim-time ticks")
    assert all(b - a == pytest.approx(0.1, abs=0.021) for a, b in zip(ticks, ticks[1:])), ticks


def test_a_timer_at_the_clocks_own_rate_fires_on_every_tick(node_pair: tuple[Node, Node]) -> None:
    """Sim time is steps times the step (1.05 may be 1.0499999999999998) and deadlines add up periods: a tick
    landing on a deadline is on time, so a 20 Hz timer on a 20 Hz clock fires on every tick, not every other."""
    talker, listener = node_pair
    ticks: list[float] = []
    done = threading.Event()

    fired = threading.Event()

    def tick() -> None:
        ticks.append(listener.now())
        fired.set()
        if len(ticks) == 30:
            done.set()

    listener.create_timer(0.05, tick)
    clock = talker.create_publisher(Clock, "clock", QoS(depth=1))
    # lockstep: the next clock goes out once this one has fired the timer (or plainly did not), so a busy machine
    # cannot merge two clocks into one delivery and make a gap the timer did not cause
    for step in range(0, 2000, 5):  # a 0.01 s step, a clock every 5 steps
        fired.clear()
        clock.publish(Clock(Time.from_sec(step * 0.01)))
        fired.wait(
            0.5 if ticks else 0.05
        )  # a clock that does not fire the timer makes the gap the assert reports
        if done.is_set():
            break
    _wait(done, "thirty ticks")
    gaps = [round(b - a, 6) for a, b in zip(ticks, ticks[1:])]
    assert all(g == pytest.approx(0.05, abs=1e-6) for g in gaps), gaps


def test_a_node_answers_with_its_counters(node_pair: tuple[Node, Node], bus: zenoh.Session) -> None:
    import json

    talker, listener = node_pair
    got = threading.Event()
    listener.create_subscription(Bool, "counted", lambda _m: got.set(), RELIABLE)
    pub = talker.create_publisher(Bool, "counted")
    talker.declare_ready()
    listener.declare_ready()
    wait_until(pub.has_subscribers, 5.0, "the publisher never matched the subscriber")
    for _ in range(3):
        pub.publish(Bool(True))
    wait_until(
        lambda: listener.stats.received.get(talker.key("counted"), 0) == 3,
        5.0,
        lambda: f"received so far: {listener.stats.received}",
    )
    by_node: dict[tuple[str, str], dict] = {}

    def both_answered() -> bool:
        replies = bus.get(
            "@zendock/stats/**",
            timeout=2.0,
            target=zenoh.QueryTarget.ALL,
            consolidation=zenoh.ConsolidationMode.NONE,
        )
        for reply in replies:
            if reply.ok is not None:
                body = json.loads(reply.ok.payload.to_bytes())
                by_node[(body["namespace"], body["node"])] = body
        return {(talker.namespace, "talker"), (listener.namespace, "listener")} <= set(by_node)

    wait_until(both_answered, 10.0, lambda: f"answers so far: {sorted(by_node)}")
    assert by_node[(talker.namespace, "talker")]["published"] == {talker.key("counted"): 3}
    assert by_node[(listener.namespace, "listener")]["received"][talker.key("counted")] == 3


def test_callback_exception_does_not_stop_the_node(node_pair: tuple[Node, Node], bus: zenoh.Session) -> None:
    talker, listener = node_pair
    survived = threading.Event()

    def flaky(msg: Bool) -> None:
        if msg.data:
            raise RuntimeError("boom")
        survived.set()

    listener.create_subscription(Bool, "flaky", flaky)
    # the token follows the subscriber on the same session: once the router has it, puts are routed
    wait_until(
        lambda: any("/sub/" in k and k.endswith("/flaky") for k in liveliness_keys(bus)),
        5.0,
        "the subscription's token never appeared",
    )
    pub = talker.create_publisher(Bool, "flaky")
    pub.publish(Bool(True))
    pub.publish(Bool(False))
    _wait(survived, "the second message after a failing callback")
    assert listener.stats.callback_errors == 1


def test_requests(node_pair: tuple[Node, Node], bus: zenoh.Session) -> None:
    talker, listener = node_pair

    def handler(req: Twist) -> Twist:
        if req.linear.x < 0:
            raise ValueError("linear.x must be positive")
        return Twist.planar(req.linear.x * 2, 0.0)

    listener.create_service(ECHO, "double", handler)
    wait_until(
        lambda: any("/srv/" in k and k.endswith("/double") for k in liveliness_keys(bus)),
        5.0,
        "the service's token never appeared",
    )
    assert talker.call(ECHO, "double", Twist.planar(1.5, 0.0)).linear.x == 3.0
    with pytest.raises(ServiceError, match="must be positive"):
        talker.call(ECHO, "double", Twist.planar(-1.0, 0.0))
    replies = list(bus.get(listener.key("double"), payload=b"\xc1", timeout=2.0))
    assert (
        replies and replies[0].err is not None and "not valid msgpack" in replies[0].err.payload.to_string()
    )
    with pytest.raises(ServiceError, match="no service answered"):
        call_service(bus, listener.key("absent"), ECHO, Twist(), timeout_s=0.5)

    results: list[tuple[object, object]] = []
    done = threading.Event()
    talker_spin = threading.Thread(target=talker.spin, daemon=True)
    talker_spin.start()
    talker.call_async(
        ECHO, "double", Twist.planar(2.0, 0.0), lambda r, e: (results.append((r, e)), done.set())
    )
    _wait(done, "the asynchronous reply")
    talker.shutdown()
    talker_spin.join(5)
    response, error = results[0]
    assert error is None and isinstance(response, Twist) and response.linear.x == 4.0


def test_publisher_refuses_invalid_message(node_pair: tuple[Node, Node]) -> None:
    talker, _ = node_pair
    pub = talker.create_publisher(Twist, "cmd_vel")
    with pytest.raises(Exception, match="must be finite"):
        pub.publish(Twist.planar(float("nan"), 0.0))
    with pytest.raises(Exception, match="expects geometry_msgs/msg/Twist"):
        pub.publish(Bool(True))  # type: ignore[arg-type]


def test_keys_deletes_and_declared_types(node_pair: tuple[Node, Node], bus: zenoh.Session) -> None:
    """Exact and wildcard keys reach the callback; a DELETE is ignored; an empty PUT or another type is rejected."""
    talker, listener = node_pair
    exact: list[Twist] = []
    keyed: list[tuple[str, float]] = []
    done = threading.Event()

    def on_keyed(key: str, msg: Twist) -> None:
        keyed.append((key, msg.linear.x))
        if len(keyed) == 2:
            done.set()

    listener.create_subscription(Twist, "robot/cmd_vel", exact.append, RELIABLE)
    listener.create_subscription(Twist, "*/cmd_vel", on_keyed, RELIABLE, with_key=True)
    wait_until(
        lambda: sum("cmd_vel" in k for k in liveliness_keys(bus)) >= 2, 5.0, "the subscriptions' tokens"
    )
    key = talker.key("robot/cmd_vel")
    bus.delete(key)
    bus.put(key, b"")
    bus.put(
        key,
        Twist.planar(9.0, 0.0).encode(),
        encoding=zenoh.Encoding("application/msgpack;geometry_msgs/msg/Point"),
    )
    talker.create_publisher(Twist, "robot/cmd_vel").publish(Twist.planar(1.0, 0.0))
    talker.create_publisher(Twist, "other/cmd_vel").publish(Twist.planar(2.0, 0.0))
    _wait(done, "two twists on the wildcard")
    wait_until(lambda: len(exact) == 1, 5.0, lambda: f"exact subscription got {exact}")
    assert exact == [Twist.planar(1.0, 0.0)]
    assert sorted(keyed) == [(talker.key("other/cmd_vel"), 2.0), (key, 1.0)]
    rejected = listener.stats.rejected
    wait_until(lambda: rejected.get(key, 0) >= 4, 5.0, lambda: f"rejections so far: {dict(rejected)}")
    assert rejected[key] == 4  # the empty PUT and the Point, once per subscription; never the DELETE
    assert listener.stats.received[key] == 2 and listener.stats.received[talker.key("other/cmd_vel")] == 1


def test_an_undecoded_subscription_gets_the_payload_and_still_refuses_another_type(
    node_pair: tuple[Node, Node], bus: zenoh.Session
) -> None:
    """The bytes as published reach the callback undecoded; a payload declared as another type does not."""
    talker, listener = node_pair
    got: list[tuple[str, bytes]] = []
    done = threading.Event()

    def on_payload(key: str, payload: bytes) -> None:
        got.append((key, payload))
        done.set()

    listener.create_subscription(Twist, "*/cmd_vel", on_payload, RELIABLE, with_key=True, undecoded=True)
    wait_until(lambda: any("cmd_vel" in k for k in liveliness_keys(bus)), 5.0, "the subscription's token")
    key = talker.key("robot/cmd_vel")
    bus.put(
        key,
        Twist.planar(9.0, 0.0).encode(),
        encoding=zenoh.Encoding("application/msgpack;geometry_msgs/msg/Point"),
    )
    rejected = listener.stats.rejected
    wait_until(lambda: rejected.get(key, 0) >= 1, 5.0, lambda: f"rejections so far: {dict(rejected)}")
    talker.create_publisher(Twist, "robot/cmd_vel").publish(Twist.planar(1.0, 0.0))
    _wait(done, "the twist's payload")
    assert got == [(key, Twist.planar(1.0, 0.0).encode())]
    assert Twist.decode(got[0][1]) == Twist.planar(1.0, 0.0)
    assert rejected[key] == 1 and listener.stats.received[key] == 1
