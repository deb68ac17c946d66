"""The battery and pose services as real processes, with the test playing the simulator on the bus."""

from __future__ import annotations

import math
import threading
from collections.abc import Iterator

import msgpack
import pytest
import zenoh

from shared import topics
from shared.geometry import Pose2D
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest
from shared.messages import (
    BatteryState,
    Clock,
    DockContact,
    Float64MultiArray,
    Header,
    Odometry,
    PoseWithCovarianceStamped,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
    Twist,
    TwistWithCovariance,
)
from shared.names import topic_key
from shared.node import SENSOR_DATA, Node, ServiceError, call_service
from tests.support.bus import KeyRecorder
from tests.support.processes import ServiceProcess, wait_until

STEP_S = 0.02  # sim seconds per tick
TICK_PERIOD_S = 0.01  # wall seconds per tick: the sim runs at twice real time


class FakeSimulator:
    """Plays the simulator: every tick advances the clock and publishes what the test has set.

    ``contact`` None keeps ``dock_contact`` silent; ``tf_links`` / ``static_links`` are
    ``(parent, child, Pose2D)`` published on ``tf`` every tick and on ``tf_static`` every sim second.
    """

    def __init__(self, session: zenoh.Session, namespace: str, start_s: float = 100.0) -> None:
        self.node = Node("fake_simulator", session, namespace)
        self._clock = self.node.create_publisher(Clock, topics.CLOCK)
        self._odom = self.node.create_publisher(Odometry, topics.ODOM, SENSOR_DATA)
        self._contact = self.node.create_publisher(DockContact, topics.DOCK_CONTACT)
        self._tf = self.node.create_publisher(TFMessage, topics.TF, SENSOR_DATA)
        self._tf_static = self.node.create_publisher(TFMessage, topics.TF_STATIC)
        self._lock = threading.Condition()
        self.sim_time_s = start_s
        self.linear_mps = 0.0
        self.contact: bool | None = False
        self.tf_links: list[tuple[str, str, Pose2D]] = []
        self.static_links: list[tuple[str, str, Pose2D]] = []
        self._next_static_s = start_s
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="fake-simulator", daemon=True)
        self._thread.start()

    def set(self, **state: object) -> None:
        with self._lock:
            for name, value in state.items():
                if not hasattr(self, name):
                    raise AttributeError(name)
                setattr(self, name, value)
            if "sim_time_s" in state or "static_links" in state:
                self._next_static_s = self.sim_time_s

    def _run(self) -> None:
        while not self._stop.wait(TICK_PERIOD_S):  # paces the simulated clock; no test waits on it
            with self._lock:
                self.sim_time_s += STEP_S
                self._tick(self.sim_time_s)
                self._lock.notify_all()

    def advance(self, duration_s: float, timeout_s: float = 10.0) -> None:
        """Return once the simulated clock has moved ``duration_s`` on from now."""
        with self._lock:
            until_s = self.sim_time_s + duration_s
            if not self._lock.wait_for(lambda: self.sim_time_s >= until_s, timeout_s):
                raise AssertionError(
                    f"sim time stuck at {self.sim_time_s:.3f} s, waiting for {until_s:.3f} s"
                )

    @staticmethod
    def _transforms(links: list[tuple[str, str, Pose2D]], stamp: Time) -> TFMessage:
        return TFMessage(
            [
                TransformStamped(Header(stamp, parent), child, Transform.from_pose2d(pose))
                for parent, child, pose in links
            ]
        )

    def _tick(self, now_s: float) -> None:
        stamp = Time.from_sec(now_s)
        self._clock.publish(Clock(stamp))
        twist = TwistWithCovariance(twist=Twist.planar(self.linear_mps, 0.0))
        self._odom.publish(Odometry(header=Header(stamp, "odom"), child_frame_id="base_link", twist=twist))
        if self.contact is not None:
            self._contact.publish(
                DockContact(header=Header(stamp, "base_link"), dock_id="home", mated=self.contact)
            )
        if self.tf_links:
            self._tf.publish(self._transforms(self.tf_links, stamp))
        if self.static_links and now_s >= self._next_static_s:
            self._tf_static.publish(self._transforms(self.static_links, Time()))
            self._next_static_s = now_s + 1.0

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5.0)
        self.node.close()


@pytest.fixture
def sim(bus: zenoh.Session, namespace: str) -> Iterator[FakeSimulator]:
    simulator = FakeSimulator(bus, namespace)
    yield simulator
    simulator.close()


def wait_for_log(proc: ServiceProcess, text: str, timeout_s: float = 10.0) -> None:
    wait_until(
        lambda: text in proc.output(), timeout_s, lambda: f"{text!r} not in output:\n{proc.output()[-3000:]}"
    )


# --- battery ---------------------------------------------------------------------------------------


def test_battery_drains_charges_and_answers_set_state(
    spawn,
    bus: zenoh.Session,
    namespace: str,
    sim: FakeSimulator,  # type: ignore[no-untyped-def]
) -> None:
    status = KeyRecorder(bus, topic_key(namespace, topics.BATTERY_STATUS), BatteryState)
    battery = spawn(
        "battery",
        "-p",
        "use_sim_time=true",
        "-p",
        "initial_percentage=0.8",
        "-p",
        "drain_scale=100",
        "-p",
        "charge_scale=100",
    )

    # A valid BatteryState, discharging at the base load.
    first = status.wait_for(timeout_s=15.0)
    assert first.percentage == pytest.approx(0.8, abs=0.01)
    assert first.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_DISCHARGING
    assert first.current == pytest.approx(-0.4)
    assert 9.0 < first.voltage < 12.6
    assert first.capacity == 2.0 and first.charge == pytest.approx(first.percentage * 2.0)
    assert first.header.stamp.to_sec() > 99.0  # stamped on sim time

    # Drains; motion adds to the load.
    status.wait_for(lambda m: m.percentage < first.percentage - 0.002, timeout_s=5.0)
    sim.set(linear_mps=0.5)
    moving = status.wait_for(lambda m: m.current == pytest.approx(-1.4), timeout_s=5.0, after=status.count)

    # Charges while mated.
    sim.set(linear_mps=0.0, contact=True)
    charging = status.wait_for(
        lambda m: m.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_CHARGING,
        timeout_s=5.0,
        after=status.count,
    )
    assert charging.current == pytest.approx(1.0)
    status.wait_for(lambda m: m.percentage > charging.percentage + 0.002, timeout_s=5.0, after=status.count)
    assert moving.percentage < first.percentage

    # Garbage on dock_contact is rejected and the service carries on.
    contact_key = topic_key(namespace, topics.DOCK_CONTACT)
    bus.put(contact_key, b"\xc1\xc1 not msgpack")
    bus.put(contact_key, msgpack.packb({"mated": "yes"}))
    wait_for_log(battery, f"rejected message on {contact_key}")
    sim.set(contact=False)
    status.wait_for(
        lambda m: m.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_DISCHARGING,
        timeout_s=5.0,
        after=status.count,
    )
    assert battery.alive()

    # A silent dock_contact counts as open contacts.
    sim.set(contact=True)
    status.wait_for(
        lambda m: m.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_CHARGING, 5.0, status.count
    )
    sim.set(contact=None)
    status.wait_for(
        lambda m: m.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_DISCHARGING, 5.0, status.count
    )
    wait_for_log(battery, "no dock_contact for more than 1 s")

    # set_state: just above a quarter with a demo drain, then a clean downward crossing.
    service_key = topic_key(namespace, topics.BATTERY_SET_STATE)
    sim.set(linear_mps=0.5)
    mark = status.count
    reply = call_service(
        bus, service_key, SET_BATTERY_STATE, SetBatteryStateRequest(percentage=0.26, drain_scale=20.0)
    )
    assert reply.state.percentage == pytest.approx(0.26, abs=1e-6)
    assert (reply.drain_scale, reply.charge_scale, reply.frozen) == (20.0, 100.0, False)
    above = status.wait_for(lambda m: 0.25 <= m.percentage <= 0.26 + 1e-6, timeout_s=5.0, after=mark)
    below = status.wait_for(lambda m: m.percentage < 0.25, timeout_s=10.0, after=mark)
    assert below.header.stamp.to_sec() > above.header.stamp.to_sec()

    # A bad percentage is refused by the service with a reason, and changes nothing.
    with pytest.raises(ServiceError, match=r"percentage must be within \[0, 1\], got inf"):
        call_service(bus, service_key, SET_BATTERY_STATE, SetBatteryStateRequest(percentage=math.inf))
    raw = SetBatteryStateRequest().to_dict() | {"percentage": 1.5}
    replies = list(bus.get(service_key, payload=msgpack.packb(raw), timeout=5.0))
    assert replies and replies[0].err is not None
    assert "field 'percentage': must be within [0.0, 1.0], got 1.5" in replies[0].err.payload.to_string()
    latest = status.wait_for(timeout_s=5.0, after=status.count)
    assert latest.percentage < 0.25

    # Frozen holds the percentage.
    frozen = call_service(bus, service_key, SET_BATTERY_STATE, SetBatteryStateRequest(frozen=True))
    mark = status.count
    held = [status.wait_for(timeout_s=5.0, after=mark + i) for i in range(5)]
    assert {m.percentage for m in held} == {frozen.state.percentage}

    # A simulator reset (clock back to ~0) neither drains nor fills the battery.
    call_service(bus, service_key, SET_BATTERY_STATE, SetBatteryStateRequest(frozen=False))
    before = status.wait_for(timeout_s=5.0, after=status.count)
    sim.set(sim_time_s=1.0)
    after = status.wait_for(lambda m: m.header.stamp.to_sec() < 50.0, timeout_s=5.0, after=status.count)
    assert after.percentage == pytest.approx(before.percentage, abs=0.01)
    wait_for_log(battery, "clock jumped back")
    assert battery.alive()
    status.close()


def test_battery_on_wall_time_publishes_at_its_rate(spawn, bus: zenoh.Session, namespace: str) -> None:  # type: ignore[no-untyped-def]
    status = KeyRecorder(bus, topic_key(namespace, topics.BATTERY_STATUS), BatteryState)
    spawn("battery", "-p", "publish_rate_hz=10", "-p", "initial_percentage=0.5")
    first = status.wait_for(timeout_s=15.0)
    eleventh = status.wait_for(timeout_s=5.0, after=10)  # the recorder saw every message: first is number 0
    span_s = eleventh.header.stamp.to_sec() - first.header.stamp.to_sec()
    assert 0.8 < span_s < 1.5  # ten periods of 0.1 s on the wall clock
    assert eleventh.percentage < first.percentage  # the base load drains it, no simulator needed
    assert first.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_DISCHARGING
    status.close()


def test_battery_refuses_bad_parameters(spawn) -> None:  # type: ignore[no-untyped-def]
    out_of_range = spawn("battery", "-p", "initial_percentage=1.5")
    unknown = spawn("battery", "-p", "drain_rate=3")
    assert out_of_range.proc.wait(20) == 2
    assert unknown.proc.wait(20) == 2
    assert "initial_percentage: must be at most 1.0" in out_of_range.output()
    assert "drain_rate: unknown key" in unknown.output()


# --- pose ------------------------------------------------------------------------------------------

MAP_TO_ODOM = Pose2D(1.0, 2.0, 0.5)
ODOM_TO_BASE = Pose2D(0.5, -0.3, 2.9)  # the composed yaw, 3.4 rad, must come out wrapped
BASE_TO_LIDAR = Pose2D(0.12, 0.0, 0.0)


def close_to(msg: Float64MultiArray, expected: Pose2D, tol: float = 1e-6) -> bool:
    x, y, yaw = (float(v) for v in msg.data)
    return (
        abs(x - expected.x) < tol
        and abs(y - expected.y) < tol
        and abs(math.remainder(yaw - expected.yaw, 2 * math.pi)) < tol
    )


def test_pose_waits_for_tf_then_publishes_map_to_base_link(
    spawn,
    bus: zenoh.Session,
    namespace: str,
    sim: FakeSimulator,  # type: ignore[no-untyped-def]
) -> None:
    poses = KeyRecorder(bus, topic_key(namespace, topics.POSE2D), Float64MultiArray)
    amcl_poses = KeyRecorder(bus, topic_key(namespace, topics.AMCL_POSE), PoseWithCovarianceStamped)
    pose = spawn("pose", "-p", "use_sim_time=true")

    # The clock runs but no transform exists: it says so and publishes nothing.
    wait_for_log(pose, "no transform map -> base_link yet", timeout_s=15.0)
    sim.advance(1.0)
    assert poses.count == 0

    sim.set(tf_links=[("map", "odom", MAP_TO_ODOM), ("odom", "base_link", ODOM_TO_BASE)])
    expected = MAP_TO_ODOM.compose(ODOM_TO_BASE)
    msg = poses.wait_for(lambda m: close_to(m, expected), timeout_s=10.0)
    assert [(d.label, d.size, d.stride) for d in msg.layout.dim] == [("pose2d", 3, 3)]
    assert -math.pi <= msg.data[2] < math.pi
    wait_for_log(pose, "transform map -> base_link available")

    # The robot moves: the pose follows.
    moved = Pose2D(-0.4, 0.7, -1.2)
    sim.set(tf_links=[("map", "odom", MAP_TO_ODOM), ("odom", "base_link", moved)])
    poses.wait_for(lambda m: close_to(m, MAP_TO_ODOM.compose(moved)), timeout_s=10.0, after=poses.count)
    # As Nav2's amcl publishes it (the pose service stands in for amcl): the same pose, stamped, in map.
    there = MAP_TO_ODOM.compose(moved)
    amcl = amcl_poses.wait_for(lambda m: m.pose.pose.to_pose2d().distance_to(there) < 1e-6, timeout_s=10.0)
    assert amcl.header.frame_id == "map" and amcl.header.stamp.to_sec() > 0.0
    assert abs(amcl.pose.pose.to_pose2d().yaw - there.yaw) < 1e-6

    # tf stops: once the newest transform is older than max_transform_age_s (1 s) nothing more is published.
    sim.set(tf_links=[])
    wait_for_log(pose, "more than max_transform_age_s=1")
    mark = poses.count
    sim.advance(1.0)
    assert poses.count - mark <= 1  # at most one in flight when the log line was read; 10 Hz would give ~10
    poses.close()
    amcl_poses.close()


def test_pose_of_lidar_link_through_tf_static(
    spawn,
    bus: zenoh.Session,
    namespace: str,
    sim: FakeSimulator,  # type: ignore[no-untyped-def]
) -> None:
    poses = KeyRecorder(bus, topic_key(namespace, topics.POSE2D), Float64MultiArray)
    sim.set(
        tf_links=[("map", "odom", MAP_TO_ODOM), ("odom", "base_link", ODOM_TO_BASE)],
        static_links=[("base_link", "lidar_link", BASE_TO_LIDAR)],
    )
    spawn("pose", "-p", "use_sim_time=true", "-p", "target_frame=lidar_link")
    expected = MAP_TO_ODOM.compose(ODOM_TO_BASE).compose(BASE_TO_LIDAR)
    poses.wait_for(lambda m: close_to(m, expected), timeout_s=15.0)
    poses.close()


def test_pose_refuses_bad_parameters(spawn) -> None:  # type: ignore[no-untyped-def]
    not_a_string = spawn("pose", "-p", "target_frame=42")
    unknown = spawn("pose", "-p", "frame=lidar_link")
    assert not_a_string.proc.wait(20) == 2
    assert unknown.proc.wait(20) == 2
    assert "target_frame: expected text, got int" in not_a_string.output()
    assert "frame: unknown key" in unknown.output()
