"""``<nav2 node>/get_state`` answered ``active`` for each Nav2 node a zendock service stands in for
(:mod:`shared.nav2_stand_ins`); the runtime attaches them to every service's node, as its parameters."""

from __future__ import annotations

from shared.interfaces.lifecycle import ACTIVE, GET_STATE, GetStateRequest, GetStateResponse
from shared.nav2_stand_ins import get_state_service, stand_ins
from shared.node import Node, ServiceServer


def serve_lifecycle_states(
    node: Node, service: str
) -> list[ServiceServer[GetStateRequest, GetStateResponse]]:
    """``<nav2 node>/get_state`` on ``node`` for each Nav2 node ``service`` stands in for: ``active``."""

    def active(_request: GetStateRequest) -> GetStateResponse:
        return GetStateResponse(current_state=ACTIVE)

    return [node.create_service(GET_STATE, get_state_service(name), active) for name in stand_ins(service)]
