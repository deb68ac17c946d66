"""``zendock bench ros2``: what the ROS 2 bridge adds, per message type.

A router and the bridge run as processes; this process plays both ends. On zendock's side it publishes
a message on the zendock key (msgpack, as a service would); on ROS 2's side it announces a subscription
for the topic (rmw_zenoh's liveliness token, so the bridge forwards it) and receives the CDR on the
topic's data key. Each message's header stamp carries its index, so every arrival is matched with its
send time. The direct path (a zendock subscriber on the zendock key, same process, same moments) is
measured alongside: the bridge's cost is the difference.

Per type (BatteryState, LaserScan, TFMessage, a 640x480 mono Image):
- latency through the bridge and direct, p50 and p99, at a paced rate;
- the bridge's CPU per forwarded message (its process's CPU time over the paced run, less its CPU time
  over an idle interval as long);
- the most messages per second it forwards when sent as fast as they can be.
"""

from __future__ import annotations

import math
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import psutil
import zenoh

from deploy.bench.processes import ServiceGroup, free_port
from deploy.percentiles import median, percentile
from shared.messages import (
    BatteryState,
    Header,
    Image,
    LaserScan,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
)
from shared.node import encoding_for
from shared.ros2 import types as ros_types
from shared.ros2.wire import SENSOR_DATA, Endpoint, EntityKind, GraphNode, data_key
from shared.schema import Message
from shared.session import SessionSpec, open_session

NAMESPACE = "bench"


@dataclass(frozen=True)
class Case:
    topic: str
    make: Callable[[Header], Message]
    rate_hz: float


def _battery(header: Header) -> Message:
    return BatteryState(header, voltage=12.1, percentage=0.7, power_supply_status=2)


def _scan(header: Header) -> Message:
    ranges = np.linspace(0.2, 8.0, 360, dtype=np.float32)
    return LaserScan(
        header, -math.pi, math.pi, math.tau / 360, 0.0, 0.1, 0.12, 12.0, ranges, np.zeros(0, np.float32)
    )


def _tf(header: Header) -> Message:
    return TFMessage(
        [
            TransformStamped(header, "base_link", Transform()),
            TransformStamped(Header(header.stamp, "map"), "odom", Transform()),
        ]
    )


_PIXELS = np.random.default_rng(1).integers(0, 255, 640 * 480, dtype=np.uint8)


def _image(header: Header) -> Message:
    return Image(header, 480, 640, "mono8", 0, 640, _PIXELS)


CASES = (
    Case("battery_status", _battery, 200.0),
    Case("scan", _scan, 200.0),
    Case("tf", _tf, 200.0),
    Case("camera/image_raw", _image, 30.0),
)


def _zendock_stamp(msg: Any) -> int:
    header = msg.transforms[0].header if isinstance(msg, TFMessage) else msg.header
    return int(header.stamp.sec)


def _stamp_of(ros_type: str, payload: bytes) -> int:
    msg = ros_types.from_cdr(payload, ros_type)
    header = msg.transforms[0].header if ros_type == "tf2_msgs/msg/TFMessage" else msg.header
    return int(header.stamp.sec)


#: The stack's pace with the bridge: which ROS 2 subscriptions a peer holds in each condition.
RTF_CONDITIONS: dict[str, tuple[tuple[str, str], ...]] = {
    "bridge, no ROS 2 peer": (),
    "peer on /battery_status": (("/battery_status", "sensor_msgs/msg/BatteryState"),),
    "peer on /scan and /tf": (("/scan", "sensor_msgs/msg/LaserScan"), ("/tf", "tf2_msgs/msg/TFMessage")),
}


def run_stack_rtf(world: str, seconds: float = 10.0) -> dict[str, float]:
    """Simulator (flat out), battery and pose, without the bridge and then with it under each condition:
    the real-time factor the simulator's clock shows."""
    from shared.messages import Clock  # noqa: PLC0415

    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory(prefix="zendock-bench-ros2-rtf-") as tmp:
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        with (
            open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))),
            ServiceGroup(
                endpoint,
                NAMESPACE,
                {
                    "simulator": ["--world", world, "-p", "rtf=max"],
                    "battery": ["-p", "use_sim_time=true"],
                    "pose": ["-p", "use_sim_time=true"],
                },
                Path(tmp),
            ) as stack,
            open_session(SessionSpec(mode="client", connect=(endpoint,))) as session,
        ):
            latest = [0.0]
            clock = session.declare_subscriber(
                f"{NAMESPACE}/clock",
                lambda s: latest.__setitem__(0, Clock.decode(s.payload.to_bytes()).clock.to_sec()),
            )

            def rtf() -> float:
                time.sleep(1.0)  # settle
                sim0, wall0 = latest[0], time.perf_counter()
                time.sleep(seconds)
                return round((latest[0] - sim0) / (time.perf_counter() - wall0), 2)

            deadline = time.monotonic() + 30.0
            while latest[0] == 0.0:
                if time.monotonic() > deadline:
                    raise RuntimeError(f"the simulator's clock never started:\n{stack.tails()}")
                time.sleep(0.05)
            out["no bridge"] = rtf()
            bridge_dir = Path(tmp) / "bridge"
            bridge_dir.mkdir()
            with ServiceGroup(endpoint, NAMESPACE, {"ros2_bridge": []}, bridge_dir) as bridge:
                time.sleep(3.0)  # started and declared
                node = GraphNode(0, str(session.info.zid()), 0, "bench_ros2_peer")
                for label, wanted in RTF_CONDITIONS.items():
                    held: list[Any] = []
                    for i, (topic, ros_type) in enumerate(wanted, start=1):
                        type_hash = ros_types.type_hash(ros_type)
                        held.append(
                            session.declare_subscriber(
                                data_key(0, topic, ros_type, type_hash), lambda _s: None
                            )
                        )
                        held.append(
                            session.liveliness().declare_token(
                                Endpoint(
                                    node, i, EntityKind.SUBSCRIPTION, topic, ros_type, type_hash, SENSOR_DATA
                                ).token_key()
                            )
                        )
                    out[label] = rtf()
                    for entity in held:
                        entity.undeclare()
                if bridge.procs["ros2_bridge"].poll() is not None:
                    raise RuntimeError(f"the bridge stopped:\n{bridge.tails()}")
            clock.undeclare()
    return out


def run_ros2_bench(messages: int = 1000, burst_s: float = 2.0) -> dict[str, Any]:
    with tempfile.TemporaryDirectory(prefix="zendock-bench-ros2-") as tmp:
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        with (
            open_session(SessionSpec(mode="router", connect=(), listen=(endpoint,))),
            ServiceGroup(endpoint, NAMESPACE, {"ros2_bridge": []}, Path(tmp)) as stack,
            open_session(SessionSpec(mode="client", connect=(endpoint,))) as session,
        ):
            bridge = psutil.Process(stack.procs["ros2_bridge"].pid)
            results = {
                case.topic: _measure(session, bridge, case, messages, burst_s, stack) for case in CASES
            }
    return {"messages_per_case": messages, "cases": results}


def _measure(
    session: zenoh.Session,
    bridge: psutil.Process,
    case: Case,
    messages: int,
    burst_s: float,
    stack: ServiceGroup,
) -> dict[str, Any]:
    msg_type = type(case.make(Header()))
    ros_type = msg_type.TYPE_NAME
    topic = "/" + case.topic
    type_hash = ros_types.type_hash(ros_type)
    sent: dict[int, float] = {}
    bridged: dict[int, float] = {}
    direct: dict[int, float] = {}
    arrivals = [0]
    arrived = threading.Condition()

    def on_ros(sample: zenoh.Sample) -> None:
        now = time.perf_counter()
        index = _stamp_of(ros_type, sample.payload.to_bytes())
        with arrived:
            arrivals[0] += 1
            bridged.setdefault(index, now)
            arrived.notify_all()

    def on_direct(sample: zenoh.Sample) -> None:
        now = time.perf_counter()
        direct.setdefault(_zendock_stamp(msg_type.decode(sample.payload.to_bytes())), now)

    key = f"{NAMESPACE}/{case.topic}"
    ros_sub = session.declare_subscriber(data_key(0, topic, ros_type, type_hash), on_ros)
    direct_sub = session.declare_subscriber(key, on_direct)
    node = GraphNode(0, str(session.info.zid()), 0, "bench_ros2_peer")
    token = session.liveliness().declare_token(
        Endpoint(node, 1, EntityKind.SUBSCRIPTION, topic, ros_type, type_hash, SENSOR_DATA).token_key()
    )
    publisher = session.declare_publisher(key, encoding=encoding_for(ros_type))
    try:
        # Wait until the bridge forwards (it saw the token and subscribed): probe with index 0.
        deadline = time.monotonic() + 20.0
        while 0 not in bridged:
            if time.monotonic() > deadline:
                raise RuntimeError(f"the bridge never forwarded {key}:\n{stack.tails()}")
            publisher.put(case.make(Header(Time(0, 0), "base_link")).encode())
            with arrived:
                arrived.wait(0.1)
        payloads = [case.make(Header(Time(i, 0), "base_link")).encode() for i in range(1, messages + 1)]
        period = 1.0 / case.rate_hz
        # The bridge's own ticking (timers, the graph) over as long as the paced run: subtracted below.
        idle_before = _cpu_s(bridge)
        time.sleep(messages * period)
        idle_s = _cpu_s(bridge) - idle_before
        cpu_before = _cpu_s(bridge)
        start = time.perf_counter()
        for i, payload in enumerate(payloads, start=1):
            target = start + (i - 1) * period
            while time.perf_counter() < target:
                time.sleep(min(0.002, max(0.0, target - time.perf_counter())))
            sent[i] = time.perf_counter()
            publisher.put(payload)
        _wait_for(lambda: len(bridged) > messages, 5.0, arrived)
        cpu_s = max(0.0, _cpu_s(bridge) - cpu_before - idle_s)
        paced = {i for i in sent if i in bridged}
        through = sorted(bridged[i] - sent[i] for i in paced)
        straight = sorted(direct[i] - sent[i] for i in sent if i in direct)
        # As fast as they go: how many the bridge forwards in burst_s.
        before = arrivals[0]
        burst_payload = case.make(Header(Time(10**6, 0), "base_link")).encode()
        burst_sent = 0
        burst_start = time.perf_counter()
        while time.perf_counter() - burst_start < burst_s:
            publisher.put(burst_payload)
            burst_sent += 1
        _wait_for(lambda: False, 0.5, arrived)  # the last ones in flight
        burst_received = arrivals[0] - before
    finally:
        token.undeclare()
        publisher.undeclare()
        ros_sub.undeclare()
        direct_sub.undeclare()
    return {
        "ros_type": ros_type,
        "payload_bytes": len(payloads[0]),
        "paced_rate_hz": case.rate_hz,
        "delivered": len(paced),
        "bridge_p50_ms": _ms(median(through)),
        "bridge_p99_ms": _ms(percentile(through, 0.99)),
        "direct_p50_ms": _ms(median(straight)),
        "direct_p99_ms": _ms(percentile(straight, 0.99)),
        "added_p50_ms": _ms(median(through) - median(straight)),
        "bridge_cpu_us_per_message": round(1e6 * cpu_s / max(1, len(paced)), 1),
        "burst_sent_per_s": round(burst_sent / burst_s),
        "burst_forwarded_per_s": round(burst_received / burst_s),
    }


def _cpu_s(process: psutil.Process) -> float:
    times = process.cpu_times()
    return float(times.user + times.system)


def _wait_for(predicate: Callable[[], bool], timeout_s: float, cv: threading.Condition) -> None:
    deadline = time.monotonic() + timeout_s
    with cv:
        while not predicate() and time.monotonic() < deadline:
            cv.wait(0.05)


def _ms(seconds: float) -> float | None:
    return None if math.isnan(seconds) else round(1000.0 * seconds, 3)
