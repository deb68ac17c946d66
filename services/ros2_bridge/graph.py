"""The ROS 2 graph the bridge shows: each zendock service as a ROS 2 node, present while the service is.

Every zendock service announces itself with a liveliness token (``@zendock/node/<ns>/<name>``); the bridge
declares a service's ROS 2 tokens (its node and its publishers, subscriptions and services) while that
token exists and withdraws them when it goes, so ``ros2 node list`` shows a stopped planner as gone, as it
would a ROS 2 node. The bridge's own node is always there.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from shared.ros2.wire import Endpoint, GraphNode


class GraphMirror:
    """ROS 2 tokens per zendock service; ``declare(key)`` makes a token, ``token.undeclare()`` ends it."""

    def __init__(self, nodes: dict[str, GraphNode], declare: Callable[[str], Any], always: str) -> None:
        self.nodes = nodes
        self._declare = declare
        self._keys: dict[str, list[str]] = {name: [node.token_key()] for name, node in nodes.items()}
        self._live: dict[str, list[Any]] = {}
        self._always = always
        self.present(always)

    def add(self, endpoint: Endpoint) -> None:
        """An endpoint of a service: announced now if the service is up, else when it comes."""
        owner = endpoint.node.name
        self._keys[owner].append(endpoint.token_key())
        if owner in self._live:
            self._live[owner].append(self._declare(endpoint.token_key()))

    def present(self, owner: str) -> bool:
        """The service is up: declare its tokens (True if this changed anything)."""
        if owner not in self._keys or owner in self._live:
            return False
        self._live[owner] = [self._declare(key) for key in self._keys[owner]]
        return True

    def absent(self, owner: str) -> bool:
        """The service went: withdraw its tokens (never the bridge's own)."""
        if owner == self._always or owner not in self._live:
            return False
        for token in self._live.pop(owner):
            token.undeclare()
        return True

    def close(self) -> None:
        for tokens in self._live.values():
            for token in tokens:
                token.undeclare()
        self._live.clear()
