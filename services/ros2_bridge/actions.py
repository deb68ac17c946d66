"""ROS 2 services and actions on zendock's servers: a request sent from ROS 2 is a zendock request, relayed.

A plain service (Nav2's ``get_state``, see :data:`SERVICES`) is one queryable, relayed by
:class:`QueryRelay`; an action (:class:`ActionRelay`) is several.

An action on rmw_zenoh is three services (``<action>/_action/send_goal``, ``cancel_goal``,
``get_result``: queryables whose requests and replies are CDR with rmw_zenoh's attachment) and two
topics (``feedback``, ``status``; forwarded as any other topic, see :mod:`shared.ros2.bridge_routes`). zendock's actions
have the same parts under the same names with msgpack payloads (:mod:`shared.action`), so each ROS 2
request becomes the zendock request of the same type, the reply comes back the same way, and a
``get_result`` waits, as in ROS 2, until the goal ends. The relay holds no goal state of its own: the
zendock server is the only authority on a goal.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import zenoh

from shared.action import action_key
from shared.interface_types import CANCEL_GOAL
from shared.node import Node, ServiceError, ServiceType, ServiceUnavailable
from shared.ros2 import bridge_routes, interfaces
from shared.ros2 import types as ros_types
from shared.ros2.wire import Attachment, data_key
from shared.schema import MessageError

#: A goal's result may take as long as the goal: docking from across the room, navigation with recoveries.
RESULT_WAIT_S = 3600.0
REQUEST_WAIT_S = 10.0


@dataclass(frozen=True)
class RelayedService:
    """A service relayed (a plain one, or one of an action's three): its ROS 2 type and the zendock service
    it is relayed to."""

    part: str
    ros_type: str
    zendock: ServiceType[Any, Any]
    wait_s: float
    #: The reply when zendock's service does not answer (None: an error reply).
    unanswered: Callable[[], Any] | None = None


@dataclass(frozen=True)
class RelayedAction:
    name: str
    ros_type: str
    owner: str
    services: tuple[RelayedService, ...]


def _relayed(action: bridge_routes.BridgedAction) -> RelayedAction:
    parts = interfaces.action_parts(action.ros_type)
    return RelayedAction(
        action.name,
        action.ros_type,
        action.owner,
        (
            RelayedService("send_goal", parts["send_goal"], action.zendock.send_goal, REQUEST_WAIT_S),
            RelayedService("cancel_goal", parts["cancel_goal"], CANCEL_GOAL, REQUEST_WAIT_S),
            RelayedService("get_result", parts["get_result"], action.zendock.get_result, RESULT_WAIT_S),
        ),
    )


#: zendock's actions (:data:`shared.ros2.bridge_routes.ACTIONS`) as rmw_zenoh's services.
ACTIONS: tuple[RelayedAction, ...] = tuple(_relayed(action) for action in bridge_routes.ACTIONS)
#: zendock's plain services (:data:`shared.ros2.bridge_routes.SERVICES`), each its own part.
SERVICES: tuple[tuple[bridge_routes.BridgedService, RelayedService], ...] = tuple(
    (
        service,
        RelayedService(service.name, service.ros_type, service.zendock, service.wait_s, service.unanswered),
    )
    for service in bridge_routes.SERVICES
)


class QueryRelay:
    """Serves ROS 2 services (rmw_zenoh's queryables, CDR) by asking zendock's services of the same type.

    Each request becomes the zendock request, the reply comes back the same way; the relay keeps no state.
    """

    #: What the counters and refusals call this relay's requests.
    kind = "service"

    def __init__(
        self,
        node: Node,
        domain_id: int,
        refuse: Callable[..., None],
        count: Callable[[str], None],
    ) -> None:
        self.node = node
        self.domain_id = domain_id
        self._refuse = refuse
        self._count = count
        self._queryables: list[Any] = []

    def serve(self, ros_name: str, service: RelayedService, zendock_key: str) -> None:
        """Answer ROS 2's ``ros_name`` (fully qualified) from zendock's ``zendock_key`` (in the namespace)."""
        key = data_key(self.domain_id, ros_name, service.ros_type, ros_types.type_hash(service.ros_type))
        # complete: rmw_zenoh clients ask with target ALL_COMPLETE, as for any service
        self._queryables.append(
            self.node.session.declare_queryable(
                key, self._handler(ros_name, service, zendock_key), complete=True
            )
        )

    def _handler(
        self, where: str, service: RelayedService, zendock_key: str
    ) -> Callable[[zenoh.Query], None]:
        def on_query(query: zenoh.Query) -> None:
            # Zenoh's thread: take the bytes, leave the work (and the reply, perhaps much later) to the executor.
            payload = query.payload.to_bytes() if query.payload is not None else b""
            attachment = query.attachment.to_bytes() if query.attachment is not None else b""
            self.node.post(self._relay, where, service, zendock_key, query, payload, attachment)

        return on_query

    def _answer_to_error(self, service: RelayedService, where: str, error: ServiceError) -> Any | None:
        """A response to send instead of an error reply when zendock's server refused (None: none)."""
        return None

    def _relay(
        self,
        where: str,
        service: RelayedService,
        zendock_key: str,
        query: zenoh.Query,
        payload: bytes,
        attachment: bytes,
    ) -> None:
        kind = self.kind
        try:
            caller = Attachment.decode(attachment)
        except ValueError as exc:
            self._fail(
                query,
                f"{kind}-attachment-{service.part}",
                f"{where}: a request needs rmw_zenoh's attachment ({exc})",
            )
            return
        request_type, response_type = interfaces.service_parts(service.ros_type)
        try:
            request = ros_types.from_ros(ros_types.from_cdr(payload, request_type), service.zendock.request)
        except (ros_types.Ros2TypeError, MessageError) as exc:
            self._fail(query, f"{kind}-request-{service.part}", f"{where}: {exc}")
            return
        self._count(f"{kind} {where}")

        def answered(response: Any, error: ServiceError | None) -> None:
            if error is not None and not isinstance(error, ServiceUnavailable):
                response = self._answer_to_error(service, where, error)
            if response is None and service.unanswered is not None:
                self._refuse(
                    f"{kind}-unanswered-{service.part}",
                    "%s: zendock's service did not answer (%s): replied with the default",
                    where,
                    error,
                )
                response = service.unanswered()
            if response is None:
                self._fail(query, f"{kind}-server-{service.part}", f"{where}: zendock's server: {error}")
                return
            try:
                reply = ros_types.to_cdr(response, response_type)
            except ros_types.Ros2TypeError as exc:
                self._fail(query, f"{kind}-response-{service.part}", f"{where}: {exc}")
                return
            try:
                query.reply(
                    query.key_expr,
                    reply,
                    attachment=Attachment(caller.sequence_number, time.time_ns(), caller.gid).encode(),
                )
            finally:
                query.drop()

        self.node.call_async(service.zendock, zendock_key, request, answered, service.wait_s)

    def _fail(self, query: zenoh.Query, kind: str, reason: str) -> None:
        self._refuse(kind, "%s", reason)
        try:
            query.reply_err(reason.encode())
        finally:
            query.drop()

    def close(self) -> None:
        for queryable in self._queryables:
            queryable.undeclare()


class ActionRelay(QueryRelay):
    """Serves one ROS 2 action's services by asking zendock's server of the same name."""

    kind = "action"

    def __init__(
        self,
        node: Node,
        action: RelayedAction,
        domain_id: int,
        ros_name: str,
        refuse: Callable[..., None],
        count: Callable[[str], None],
    ) -> None:
        super().__init__(node, domain_id, refuse, count)
        self.action = action
        self.ros_name = ros_name
        for service in action.services:
            self.serve(f"{ros_name}/_action/{service.part}", service, action_key(action.name, service.part))

    def _answer_to_error(self, service: RelayedService, where: str, error: ServiceError) -> Any | None:
        if service.part != "send_goal":
            return None
        # The server answered but would not take the goal (e.g. a bad max_staging_time): to ROS 2 that is a
        # rejected goal, what ``ros2 action send_goal`` reports as "Goal was rejected".
        self._refuse(f"action-rejected-{service.part}", "%s: goal rejected: %s", where, error)
        return service.zendock.response(accepted=False, stamp=self.node.now_msg())
