"""The other robots of a fleet as the bus tells of them: where each is, its charge, its state, its plan.

Subscribed once with wildcards (``<fleet>/*/map_to_base_link_pose2d``, ``battery_status``,
``docking/state``, ``plan``), so a robot that joins later is seen too; the callbacks only store. The
traffic rule (:mod:`services.docking.traffic`) reads :meth:`PeerWatch.fresh`, and this robot's own plan
(the same wildcard brings it) with :meth:`PeerWatch.own_plan`.

Plans are kept as they arrive, undecoded: a plan is tens of kilobytes of poses, each peer's comes after
every replan, and the rule looks at one only for a robot near and face to face. Each plan is decoded
(and validated) at most once, when first asked for; one that fails is counted as rejected, as the
subscription would have counted it.
"""

from __future__ import annotations

import math

import numpy as np

from services.docking.traffic import Peer, PlanPoints
from shared import topics
from shared.geometry import Pose2D
from shared.messages import BatteryState, Float64MultiArray, Path, String
from shared.names import topic_key
from shared.node import Node, QoS
from shared.schema import MessageError

#: docking/state (the docking service's state names) of a robot that drives, and of one giving way.
UNDER_WAY_STATES = ("PATROLLING", "NAV_TO_STAGING_POSE", "RETRY")
GIVING_WAY_STATE = "GIVING_WAY"
#: A peer not heard from (pose, plan) for this long is not on the way.
MAX_AGE_S = 2.0


class _PeerState:
    __slots__ = ("battery", "plan_key", "plan_payload", "plan_points", "plan_s", "pose", "pose_s", "state")

    def __init__(self) -> None:
        self.pose: Pose2D | None = None
        self.pose_s = -math.inf
        self.battery = 1.0
        self.state = ""
        #: The latest plan as it came (None once decoded), and its points once decoded.
        self.plan_key = ""
        self.plan_payload: bytes | None = None
        self.plan_points: np.ndarray | None = None
        self.plan_s = -math.inf


class PeerWatch:
    """Every other robot in the namespace above ``node``'s; ``state_topic``: their docking state's topic."""

    def __init__(self, node: Node, state_topic: str) -> None:
        self._node = node
        self._peers: dict[str, _PeerState] = {}
        #: This robot's own latest plan (only the plan fields are used).
        self._own = _PeerState()
        fleet_namespace = node.namespace.rpartition("/")[0]
        for topic, msg_type, handler in (
            (topics.POSE2D, Float64MultiArray, self._on_pose),
            (topics.BATTERY_STATUS, BatteryState, self._on_battery),
            (state_topic, String, self._on_state),
        ):
            node.create_subscription(
                msg_type,
                topic_key(fleet_namespace, f"*/{topic}"),
                lambda key, msg, h=handler, t=topic: h(self._peer(key, t), msg),
                QoS(depth=20),
                with_key=True,
                absolute=True,
            )
        node.create_subscription(
            Path,
            topic_key(fleet_namespace, f"*/{topics.PLAN}"),
            lambda key, payload: self._on_plan(key, self._plan_holder(key), payload),
            QoS(depth=20),
            with_key=True,
            absolute=True,
            undecoded=True,
        )

    def _peer(self, key: str, topic: str) -> _PeerState | None:
        name = key[: -len(topic) - 1] if key.endswith("/" + topic) else ""
        if not name or name == self._node.namespace:
            return None
        return self._peers.setdefault(name, _PeerState())

    def _plan_holder(self, key: str) -> _PeerState | None:
        """Where a plan on ``key`` is kept: this robot's own, or a peer's."""
        if key == topic_key(self._node.namespace, topics.PLAN):
            return self._own
        return self._peer(key, topics.PLAN)

    def _on_pose(self, peer: _PeerState | None, msg: Float64MultiArray) -> None:
        if peer is not None and len(msg.data) >= 3 and np.all(np.isfinite(msg.data[:3])):
            peer.pose, peer.pose_s = Pose2D.from_seq(msg.data[:3]), self._node.now()

    def _on_battery(self, peer: _PeerState | None, msg: BatteryState) -> None:
        if peer is not None and math.isfinite(msg.percentage):
            peer.battery = float(msg.percentage)

    def _on_state(self, peer: _PeerState | None, msg: String) -> None:
        if peer is not None:
            peer.state = msg.data

    def _on_plan(self, key: str, peer: _PeerState | None, payload: bytes) -> None:
        if peer is not None:
            peer.plan_key, peer.plan_payload, peer.plan_points = key, payload, None
            peer.plan_s = self._node.now()

    def _plan_points(self, peer: _PeerState) -> np.ndarray | None:
        """The peer's latest plan's points, decoded now if not yet (None: no poses, or a malformed plan)."""
        payload, peer.plan_payload = peer.plan_payload, None
        if payload is not None:
            try:
                msg = Path.decode(payload)
            except MessageError as exc:
                self._node.reject(peer.plan_key, exc.at(key=peer.plan_key))
            else:
                points = [(p.pose.position.x, p.pose.position.y) for p in msg.poses]
                peer.plan_points = np.asarray(points, dtype=float) if points else None
        return peer.plan_points

    def own_plan(self, now: float) -> PlanPoints:
        """This robot's own plan as the traffic rule takes it (decoded when first asked for), while fresh."""
        own = self._own
        return (lambda: self._plan_points(own)) if now - own.plan_s <= MAX_AGE_S else None

    def fresh(self, now: float) -> list[Peer]:
        """The robots heard from lately, as the traffic rule sees them."""
        peers = []
        for name, p in self._peers.items():
            if p.pose is None or now - p.pose_s > MAX_AGE_S:
                continue
            plan = (lambda p=p: self._plan_points(p)) if now - p.plan_s <= MAX_AGE_S else None
            peers.append(
                Peer(name, p.pose, p.battery, p.state in UNDER_WAY_STATES, plan, p.state == GIVING_WAY_STATE)
            )
        return peers
