"""Every subscription in the contracts can hear its publishers under ROS 2's QoS rules.

A reliable reader does not match a best-effort writer in ROS 2, so a contract page that promised a
reliable subscription to a best-effort stream (perception's camera_info, the viewer's scans) told a
replacement's author, and every ROS 2 user reading the page, something no ROS 2 graph can do.
"""

from __future__ import annotations

from shared.contracts.services import CONTRACTS


def test_no_reliable_subscription_to_a_best_effort_publisher() -> None:
    best_effort = {
        (topic.name, service)
        for service, contract in CONTRACTS.items()
        for topic in contract.publishes
        if not topic.qos.reliable
    }
    mismatched = [
        f"{reader} subscribes {topic.name} reliable; {writer} publishes it best effort"
        for reader, contract in CONTRACTS.items()
        for topic in contract.subscribes
        if topic.qos.reliable
        for name, writer in sorted(best_effort)
        if name == topic.name
    ]
    assert not mismatched, "\n".join(mismatched)
