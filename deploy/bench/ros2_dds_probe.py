"""The ROS 2 side of ``python -m deploy.bench.ros2_dds``: rclpy and ROS 2 message packages only.

Run by ``.venv-ros2/bin/python`` on the face's ROS_DOMAIN_ID (loopback discovery). One JSON line per phase on
stdout, wall times in ``time.time_ns()`` (the same clock as the bench process's):

* ``idle``/``sensors``: nothing subscribed, then the sensor topics subscribed (the bench reads the face's CPU
  between the markers);
* ``battery``: each ``/battery_status`` arrival with its header stamp (the bench matches it with zendock's);
* ``cmd_vel``: round trips through the face: a rotation command on ``/cmd_vel`` until ``/odom`` shows it;
* ``dds``: the same measurements rclpy to rclpy (``--echo``: a second process answering pings and
  publishing wall-stamped BatteryState): what DDS itself costs on this machine.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from typing import Any

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import BatteryState, LaserScan, Range
from std_msgs.msg import Float64MultiArray
from tf2_msgs.msg import TFMessage

SENSORS: tuple[tuple[str, Any, Any], ...] = (
    ("/scan", LaserScan, qos_profile_sensor_data),
    ("/ultrasonic", Range, qos_profile_sensor_data),
    ("/odom", Odometry, 10),
    ("/tf", TFMessage, 10),
    ("/clock", Clock, 10),
    ("/battery_status", BatteryState, 10),
    ("/map_to_base_link_pose2d", Float64MultiArray, 10),
)


def emit(**fields: Any) -> None:
    print(json.dumps(fields), flush=True)


def spin_for(node: Node, seconds: float, until: Any = None) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if until is not None and until():
            return True
        rclpy.spin_once(node, timeout_sec=0.01)
    return bool(until and until())


def sensors(node: Node, seconds: float) -> None:
    emit(phase="idle", at=time.time_ns())
    spin_for(node, seconds)
    emit(phase="idle_end", at=time.time_ns())
    counts = {topic: 0 for topic, _, _ in SENSORS}
    subs = [
        node.create_subscription(cls, topic, lambda _m, t=topic: counts.__setitem__(t, counts[t] + 1), qos)
        for topic, cls, qos in SENSORS
    ]
    spin_for(node, 2.0)  # matched, forwarding
    for topic in counts:
        counts[topic] = 0
    emit(phase="sensors", at=time.time_ns())
    spin_for(node, seconds)
    emit(
        phase="sensors_end", at=time.time_ns(), rates_hz={t: round(n / seconds, 1) for t, n in counts.items()}
    )
    for sub in subs:
        node.destroy_subscription(sub)


def battery(node: Node, topic: str, seconds: float, phase: str) -> None:
    arrivals: list[tuple[int, int]] = []
    sub = node.create_subscription(
        BatteryState,
        topic,
        lambda m: arrivals.append(
            (m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec, time.time_ns())
        ),
        10,
    )
    spin_for(node, seconds)
    node.destroy_subscription(sub)
    emit(phase=phase, arrivals=arrivals)


def round_trips(node: Node, command: str, answer: str, answer_cls: Any, count: int, phase: str) -> None:
    """Rotate, then stop, ``count`` times: each time from the command's publication to the first answer that
    shows it (angular z of the answer's twist)."""
    latest: list[float] = [0.0]
    arrived: list[int] = [0]

    def on_answer(msg: Any) -> None:
        latest[0] = msg.twist.twist.angular.z
        arrived[0] = time.time_ns()

    sub = node.create_subscription(answer_cls, answer, on_answer, 10)
    pub = node.create_publisher(Twist, command, 10)
    spin_for(node, 10.0, lambda: pub.get_subscription_count() > 0 and arrived[0] > 0)
    samples: list[float] = []
    for i in range(count):
        turn = Twist()
        turn.angular.z = 0.5 if i % 2 == 0 else -0.5
        spin_for(node, 0.2)
        sent = time.time_ns()
        pub.publish(turn)
        if spin_for(node, 2.0, lambda t=turn.angular.z, s=sent: abs(latest[0] - t) < 0.25 and arrived[0] > s):
            samples.append((arrived[0] - sent) / 1e6)
        pub.publish(Twist())
        spin_for(node, 2.0, lambda: abs(latest[0]) < 0.05)
    node.destroy_publisher(pub)
    node.destroy_subscription(sub)
    emit(phase=phase, round_trips_ms=samples)


def echo(seconds: float) -> None:
    """The other rclpy process: /bench_ping (Twist) answered on /bench_pong (Odometry carrying its twist),
    and /bench_battery published at 5 Hz stamped with the wall time."""
    rclpy.init()
    node = Node("bench_echo")
    pong = node.create_publisher(Odometry, "/bench_pong", 10)
    battery_pub = node.create_publisher(BatteryState, "/bench_battery", 10)

    def on_ping(msg: Twist) -> None:
        answer = Odometry()
        answer.twist.twist = msg
        pong.publish(answer)

    def tick() -> None:
        msg = BatteryState()
        now = time.time_ns()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(now, 1_000_000_000)
        battery_pub.publish(msg)

    node.create_subscription(Twist, "/bench_ping", on_ping, 10)
    node.create_timer(0.2, tick)
    spin_for(node, seconds)
    node.destroy_node()
    rclpy.try_shutdown()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--echo", type=float, default=None, metavar="SECONDS")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--round-trips", type=int, default=20)
    args = parser.parse_args(argv)
    if args.echo is not None:
        echo(args.echo)
        return 0
    rclpy.init()
    node = Node("bench_probe")
    spin_for(node, 20.0, lambda: {"simulator", "battery"} <= set(node.get_node_names()))
    sensors(node, args.seconds)
    battery(node, "/battery_status", args.seconds, "battery")
    round_trips(node, "/cmd_vel", "/odom", Odometry, args.round_trips, "cmd_vel")
    peer = subprocess.Popen([sys.executable, __file__, "--echo", str(args.seconds + 40.0)])
    try:
        battery(node, "/bench_battery", args.seconds, "dds_battery")
        round_trips(node, "/bench_ping", "/bench_pong", Odometry, args.round_trips * 2, "dds_round_trip")
    finally:
        peer.terminate()
        peer.wait(timeout=10)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
