"""A test's eyes and hands inside another network namespace: watch one robot, act on command.

The test process cannot reach routers inside namespaces, so it runs this probe there
(``ip netns exec NS python -m tests.support.multihost_probe --connect EP --namespace ROBOT``) and
talks to it over pipes. Every ``--period-s`` the probe prints one JSON line with the latest of what it
saw (``"kind": "status"``: sim time, odometry stamp, position and speeds, battery, dock contact,
collisions, localisation, the nodes alive); collisions are also printed at once. Commands on stdin, one per line:

- ``trigger <percentage> <drain_scale>``: a ``battery/set_state`` request (prints ``"kind": "trigger"``);
- ``quit``: close the session and exit.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import threading
import time
from collections.abc import Sequence
from typing import Any

import zenoh

from shared import topics
from shared.interfaces.battery import SET_BATTERY_STATE, SetBatteryStateRequest
from shared.messages import BatteryState, Clock, CollisionEvent, DockContact, Float64MultiArray, Odometry
from shared.names import GRAPH_PREFIX, parse_token_key, topic_key
from shared.node import ServiceError, call_service
from shared.schema import Message, MessageError
from shared.session import SessionSpec, open_session


class RobotWatch:
    """The latest readings of one robot's keys, updated from Zenoh callbacks under a lock."""

    def __init__(self, session: zenoh.Session, namespace: str, emit: Any) -> None:
        self._lock = threading.Lock()
        self._emit = emit
        self.state: dict[str, Any] = {
            "sim_time_s": None,
            "odom_time_s": None,
            "x_m": None,
            "y_m": None,
            "linear_mps": None,
            "angular_radps": None,
            "odom_count": 0,
            "battery_percentage": None,
            "power_supply_status": None,
            "mated": None,
            "contact_count": 0,
            "collisions": 0,
            "pose2d_count": 0,
            "nodes": [],
        }
        self._nodes: set[str] = set()
        key = lambda name: topic_key(namespace, name)  # noqa: E731
        self._subscribers = [
            session.declare_subscriber(key(topics.CLOCK), self._decoded(Clock, self._on_clock)),
            session.declare_subscriber(key(topics.ODOM), self._decoded(Odometry, self._on_odom)),
            session.declare_subscriber(
                key(topics.BATTERY_STATUS), self._decoded(BatteryState, self._on_battery)
            ),
            session.declare_subscriber(
                key(topics.DOCK_CONTACT), self._decoded(DockContact, self._on_contact)
            ),
            session.declare_subscriber(
                key(topics.COLLISIONS), self._decoded(CollisionEvent, self._on_collision)
            ),
            session.declare_subscriber(key(topics.POSE2D), self._decoded(Float64MultiArray, self._on_pose2d)),
            session.liveliness().declare_subscriber(f"{GRAPH_PREFIX}/node/**", self._on_token, history=True),
        ]

    @staticmethod
    def _decoded(msg_type: type[Message], handler: Any):  # type: ignore[no-untyped-def]
        def on_sample(sample: zenoh.Sample) -> None:
            try:
                handler(msg_type.decode(sample.payload.to_bytes()))
            except MessageError:
                return

        return on_sample

    def _on_clock(self, msg: Clock) -> None:
        with self._lock:
            self.state["sim_time_s"] = msg.clock.to_sec()

    def _on_odom(self, msg: Odometry) -> None:
        with self._lock:
            self.state["odom_time_s"] = msg.header.stamp.to_sec()
            self.state["x_m"] = msg.pose.pose.position.x
            self.state["y_m"] = msg.pose.pose.position.y
            self.state["linear_mps"] = msg.twist.twist.linear.x
            self.state["angular_radps"] = msg.twist.twist.angular.z
            self.state["odom_count"] += 1

    def _on_battery(self, msg: BatteryState) -> None:
        with self._lock:
            self.state["battery_percentage"] = msg.percentage
            self.state["power_supply_status"] = msg.power_supply_status

    def _on_contact(self, msg: DockContact) -> None:
        with self._lock:
            self.state["mated"] = msg.mated
            self.state["contact_count"] += 1

    def _on_collision(self, msg: CollisionEvent) -> None:
        with self._lock:
            self.state["collisions"] += 1
        self._emit(
            {"kind": "collision", "what": msg.kind, "x": msg.x, "y": msg.y, "t": msg.header.stamp.to_sec()}
        )

    def _on_pose2d(self, _msg: Float64MultiArray) -> None:
        with self._lock:
            self.state["pose2d_count"] += 1

    def _on_token(self, sample: zenoh.Sample) -> None:
        entry = parse_token_key(str(sample.key_expr))
        if entry is None:
            return
        name = f"{entry.namespace}/{entry.node}"
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._nodes.add(name)
            else:
                self._nodes.discard(name)
            self.state["nodes"] = sorted(self._nodes)

    def snapshot(self) -> dict[str, Any]:
        with self._lock:
            return {"kind": "status", "wall_s": time.monotonic(), **self.state}


def trigger(session: zenoh.Session, namespace: str, percentage: float, drain_scale: float) -> dict[str, Any]:
    """Set the battery just above the low threshold, draining fast, as a demo run does."""
    try:
        reply = call_service(
            session,
            topic_key(namespace, topics.BATTERY_SET_STATE),
            SET_BATTERY_STATE,
            SetBatteryStateRequest(percentage=percentage, drain_scale=drain_scale),
        )
    except ServiceError as exc:
        return {"kind": "trigger", "ok": False, "error": str(exc)}
    return {"kind": "trigger", "ok": True, "percentage": reply.state.percentage}


def run(connect: str, namespace: str, period_s: float) -> int:
    out_lock = threading.Lock()

    def emit(record: dict[str, Any]) -> None:
        line = json.dumps(
            {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in record.items()}
        )
        with out_lock:
            sys.stdout.write(line + "\n")
            sys.stdout.flush()

    stop = threading.Event()
    with open_session(SessionSpec(mode="client", connect=(connect,))) as session:
        watch = RobotWatch(session, namespace, emit)

        def report() -> None:
            while not stop.wait(period_s):
                emit(watch.snapshot())

        reporter = threading.Thread(target=report, daemon=True)
        reporter.start()
        emit({"kind": "ready"})
        for line in sys.stdin:
            words = line.split()
            if not words:
                continue
            if words[0] == "quit":
                break
            if words[0] == "trigger" and len(words) == 3:
                emit(trigger(session, namespace, float(words[1]), float(words[2])))
            else:
                emit({"kind": "error", "error": f"unknown command {line.strip()!r}"})
        stop.set()
        reporter.join(timeout=2.0)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--connect", required=True, metavar="ENDPOINT")
    parser.add_argument("--namespace", default="")
    parser.add_argument("--period-s", type=float, default=0.05)
    args = parser.parse_args(argv)
    return run(args.connect, args.namespace, args.period_s)


if __name__ == "__main__":
    sys.exit(main())
