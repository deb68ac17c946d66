"""The bridge forwards a topic while, and only while, a ROS 2 peer subscribes to it."""

from __future__ import annotations

import pytest

from services.ros2_bridge.demand import PeerSubscriptions
from shared.ros2.wire import SENSOR_DATA, Endpoint, EntityKind, GraphNode

HASH = "RIHS01_" + "ab" * 32


def _token(session: str, entity: int, kind: EntityKind, topic: str, domain: int = 0) -> str:
    node = GraphNode(domain, session, 1, "viewer")
    return Endpoint(node, entity, kind, topic, "sensor_msgs/msg/LaserScan", HASH, SENSOR_DATA).token_key()


def test_a_topic_is_wanted_while_a_peer_subscription_lasts() -> None:
    peers = PeerSubscriptions("bridge", 0)
    first, second = (
        _token("peer", 5, EntityKind.SUBSCRIPTION, "/scan"),
        _token("peer2", 5, EntityKind.SUBSCRIPTION, "/scan"),
    )
    assert not peers.wanted("/scan")
    assert peers.appeared(first) is not None and peers.wanted("/scan")
    assert peers.appeared(first) is None  # the same token twice counts once
    peers.appeared(second)
    assert peers.vanished(first) is not None and peers.wanted("/scan")
    assert peers.vanished(second) is not None and not peers.wanted("/scan")
    assert peers.vanished(second) is None


def test_publishers_nodes_own_tokens_and_other_domains_are_no_demand() -> None:
    peers = PeerSubscriptions("bridge", 0)
    for key in (
        _token("peer", 5, EntityKind.PUBLISHER, "/scan"),
        _token("bridge", 5, EntityKind.SUBSCRIPTION, "/scan"),
        _token("peer", 5, EntityKind.SUBSCRIPTION, "/scan", domain=7),
        GraphNode(0, "peer", 1, "viewer").token_key(),
    ):
        assert peers.appeared(key) is None
    assert not peers.wanted("/scan")


def test_a_malformed_subscription_token_is_an_error() -> None:
    peers = PeerSubscriptions("bridge", 0)
    with pytest.raises(ValueError, match="token"):
        peers.appeared("@ros2_lv/0/peer/1/5/MS/%/%/viewer/%scan/LaserScan/h/::,10:,:,:,,")
