"""The fleet's other robots as the docking node keeps them: plans stay undecoded until the traffic rule asks."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import numpy as np
import pytest

from services.docking.peers import PeerWatch
from services.docking.traffic import Peer, peer_way
from shared.geometry import Pose2D
from shared.messages import BatteryState, Float64MultiArray, Path, String
from shared.node import Node
from shared.schema import MessageError

STAMP = {"sec": 0, "nanosec": 0}


class _Node:
    """What PeerWatch uses of a node: its namespace, clock, subscriptions and the rejection counter."""

    def __init__(self) -> None:
        self.namespace = "fleet/r1"
        self.clock_s = 10.0
        self.callbacks: dict[type, Callable[..., Any]] = {}
        self.undecoded: dict[type, bool] = {}
        self.rejected: list[tuple[str, MessageError]] = []

    def now(self) -> float:
        return self.clock_s

    def create_subscription(
        self,
        msg_type: type,
        key: str,
        callback: Callable[..., Any],
        qos: Any,
        *,
        with_key: bool = False,
        absolute: bool = False,
        undecoded: bool = False,
    ) -> None:
        assert with_key and absolute and key.startswith("fleet/*/")
        self.callbacks[msg_type] = callback
        self.undecoded[msg_type] = undecoded

    def reject(self, key: str, error: MessageError) -> None:
        self.rejected.append((key, error))


def _plan(points: list[tuple[float, float]]) -> Path:
    return Path.from_dict(
        {
            "header": {"frame_id": "map", "stamp": STAMP},
            "poses": [
                {
                    "header": {"frame_id": "map", "stamp": STAMP},
                    "pose": {
                        "position": {"x": x, "y": y, "z": 0.0},
                        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                    },
                }
                for x, y in points
            ],
        }
    )


def _points(plan: np.ndarray | None) -> list[list[float]]:
    assert plan is not None
    return [[float(x), float(y)] for x, y in plan]


def _watch_with_r2(node: _Node) -> PeerWatch:
    watch = PeerWatch(cast(Node, node), "docking/state")
    node.callbacks[Float64MultiArray](
        "fleet/r2/map_to_base_link_pose2d",
        Float64MultiArray.from_dict({"layout": {"dim": [], "data_offset": 0}, "data": [1.0, 2.0, 0.0]}),
    )
    node.callbacks[String]("fleet/r2/docking/state", String("PATROLLING"))
    return watch


def test_a_plan_is_kept_as_bytes_and_decoded_once_when_the_rule_asks(monkeypatch: pytest.MonkeyPatch) -> None:
    node = _Node()
    watch = _watch_with_r2(node)
    assert node.undecoded[Path] and not node.undecoded[BatteryState]
    decoded: list[bytes] = []
    real_decode = Path.decode

    def counted_decode(data: bytes) -> Path:
        decoded.append(data)
        return real_decode(data)

    monkeypatch.setattr(Path, "decode", counted_decode)
    payload = _plan([(1.0, 2.0), (2.0, 2.0), (3.0, 2.5)]).encode()
    node.callbacks[Path]("fleet/r2/plan", payload)
    (peer,) = watch.fresh(node.now())
    assert decoded == []  # arriving, and being handed to the rule, decodes nothing
    assert _points(peer.plan_points()) == [[1.0, 2.0], [2.0, 2.0], [3.0, 2.5]]
    assert _points(watch.fresh(node.now())[0].plan_points()) == [[1.0, 2.0], [2.0, 2.0], [3.0, 2.5]]
    assert decoded == [payload]
    node.callbacks[Path]("fleet/r2/plan", _plan([(5.0, 5.0), (6.0, 5.0)]).encode())
    assert _points(watch.fresh(node.now())[0].plan_points()) == [[5.0, 5.0], [6.0, 5.0]]
    assert len(decoded) == 2


def test_a_malformed_plan_is_rejected_when_asked_for_and_counts_as_none() -> None:
    node = _Node()
    watch = _watch_with_r2(node)
    node.callbacks[Path]("fleet/r2/plan", b"\x93garbage")
    (peer,) = watch.fresh(node.now())
    assert peer.plan_points() is None and peer.plan_points() is None
    assert [key for key, _ in node.rejected] == ["fleet/r2/plan"]  # counted once, not at every ask


def test_an_old_plan_is_no_plan_and_the_own_robots_is_kept_apart() -> None:
    node = _Node()
    watch = _watch_with_r2(node)
    node.callbacks[Path]("fleet/r1/plan", _plan([(0.0, 0.0), (1.0, 0.0)]).encode())
    node.callbacks[Path]("fleet/r2/plan", _plan([(1.0, 2.0), (2.0, 2.0)]).encode())
    own = watch.own_plan(node.now())
    assert callable(own) and _points(own()) == [[0.0, 0.0], [1.0, 0.0]]
    assert [peer.name for peer in watch.fresh(node.now())] == ["fleet/r2"]  # this robot is no peer
    node.clock_s += 1.0
    node.callbacks[Float64MultiArray](
        "fleet/r2/map_to_base_link_pose2d",
        Float64MultiArray.from_dict({"layout": {"dim": [], "data_offset": 0}, "data": [1.0, 2.0, 0.0]}),
    )
    node.clock_s += 1.5  # the plans are now 2.5 s old, the pose 1.5 s
    (peer,) = watch.fresh(node.now())
    assert peer.name == "fleet/r2" and peer.plan is None
    assert watch.own_plan(node.now()) is None


def test_the_way_of_a_peer_is_the_same_from_points_or_from_a_function() -> None:
    plan = np.array([[1.0, 2.0], [2.0, 2.0], [2.5, 3.0]])
    as_points = Peer("r2", Pose2D(1.0, 2.0, 0.0), 0.5, True, plan)
    as_function = Peer("r2", Pose2D(1.0, 2.0, 0.0), 0.5, True, lambda: plan)
    for a, b in zip(peer_way(as_points), peer_way(as_function), strict=True):
        np.testing.assert_array_equal(a, b)
    assert len(peer_way(as_function)) == 2
