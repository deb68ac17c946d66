"""Which ROS 2 subscriptions exist, from the graph's liveliness tokens (no Zenoh here).

The bridge forwards a zendock key only while some ROS 2 node subscribes to its topic, so a stack with
the bridge up and no ROS 2 peer does no work for it. Tokens of the bridge's own session are not demand.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from shared.ros2.wire import Endpoint, EntityKind, parse_endpoint_token


@dataclass
class PeerSubscriptions:
    own_session_id: str
    domain_id: int
    _endpoints: dict[str, Endpoint] = field(default_factory=dict)
    _per_topic: Counter[str] = field(default_factory=Counter)

    def appeared(self, token_key: str) -> Endpoint | None:
        """Record a token; the endpoint if it is a peer's subscription in this domain (else ``None``).

        ValueError for a subscription token that is not in rmw_zenoh's form."""
        endpoint = self._peer_subscription(token_key)
        if endpoint is None or token_key in self._endpoints:
            return None
        self._endpoints[token_key] = endpoint
        self._per_topic[endpoint.topic] += 1
        return endpoint

    def vanished(self, token_key: str) -> Endpoint | None:
        endpoint = self._endpoints.pop(token_key, None)
        if endpoint is not None:
            self._per_topic[endpoint.topic] -= 1
            if self._per_topic[endpoint.topic] <= 0:
                del self._per_topic[endpoint.topic]
        return endpoint

    def wanted(self, topic: str) -> bool:
        return self._per_topic.get(topic, 0) > 0

    def _peer_subscription(self, token_key: str) -> Endpoint | None:
        parts = token_key.split("/")
        if len(parts) < 6 or parts[5] != EntityKind.SUBSCRIPTION:
            return None
        endpoint = parse_endpoint_token(token_key)
        if (
            endpoint.kind is not EntityKind.SUBSCRIPTION
            or endpoint.node.session_id == self.own_session_id
            or endpoint.node.domain_id != self.domain_id
        ):
            return None
        return endpoint
