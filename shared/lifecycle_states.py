"""The lifecycle of the Nav2 nodes a zendock service stands in for (:mod:`shared.nav2_stand_ins`), served
on its node as its parameters are: ``<nav2 node>/get_state`` and ``<nav2 node>/change_state`` for each,
and ``<manager>/manage_nodes`` for each of Nav2's lifecycle managers the service hosts.

Every stand-in starts ``active``. One taken out of ``active`` refuses new goals of the actions it owns
(:data:`~shared.nav2_stand_ins.NAV2_WORK`), naming its state, and its running goal is cancelled as a
client's cancel would be (the robot stops): that is what a paused or shut-down Nav2 server does. Topics
keep flowing, and the zendock service keeps running: a ``finalized`` stand-in works again when the
service restarts (``zendock restart``), as a Nav2 node does when relaunched. A manager asks each node it
manages over the bus, in Nav2's order (:mod:`shared.lifecycle`), so it reaches nodes of other services.
"""

from __future__ import annotations

from collections.abc import Callable

from shared.endpoints import Deferred, ServiceError
from shared.interfaces.lifecycle import (
    CHANGE_STATE,
    GET_STATE,
    MANAGE_LIFECYCLE_NODES,
    ChangeStateRequest,
    ChangeStateResponse,
    GetStateRequest,
    GetStateResponse,
    ManageLifecycleNodesRequest,
    ManageLifecycleNodesResponse,
    State,
    Transition,
)
from shared.lifecycle import NodeLifecycle, managed_state, plan
from shared.nav2_stand_ins import (
    NAV2_WORK,
    LifecycleManager,
    change_state_service,
    get_state_service,
    managers_hosted_by,
    stand_ins,
)
from shared.node import Node

#: How long a manager waits for each node's answer (s): a node in another process answers in milliseconds.
CHANGE_STATE_TIMEOUT_S = 5.0


class StandInLifecycles:
    """The lifecycle of each Nav2 node ``service`` stands in for, and the managers it hosts, on ``node``."""

    def __init__(self, node: Node, service: str) -> None:
        self._node = node
        self.nodes = {name: NodeLifecycle(name) for name in stand_ins(service)}
        # the node holds its services and closes them with itself
        for name in self.nodes:
            node.create_service(GET_STATE, get_state_service(name), self._getter(name))
            node.create_service(CHANGE_STATE, change_state_service(name), self._changer(name))
        for manager in managers_hosted_by(service):
            node.create_service(MANAGE_LIFECYCLE_NODES, manager.manage_nodes, self._manager(manager))
        if self.nodes:
            node.work_gate = self.refusal

    def refusal(self, action: str) -> str | None:
        """Why a goal of ``action`` is refused now (its Nav2 node is not active), or None."""
        lifecycle = self.nodes.get(NAV2_WORK.get(action, ""))
        if lifecycle is None or lifecycle.active:
            return None
        return (
            f"{lifecycle.name} is {lifecycle.state.label}: it takes {action} goals only when active "
            f"(its lifecycle manager's STARTUP or RESUME activates it)"
        )

    # --- one node ---------------------------------------------------------------------------------

    def _getter(self, name: str) -> Callable[[GetStateRequest], GetStateResponse]:
        return lambda _request: self._get(name)

    def _changer(self, name: str) -> Callable[[ChangeStateRequest], ChangeStateResponse]:
        return lambda request: self._change(name, request)

    def _manager(
        self, manager: LifecycleManager
    ) -> Callable[[ManageLifecycleNodesRequest], Deferred[ManageLifecycleNodesResponse]]:
        return lambda request: self._manage(manager, request)

    def _get(self, name: str) -> GetStateResponse:
        state = self.nodes[name].state
        return GetStateResponse(current_state=State(id=int(state), label=state.label))

    def _change(self, name: str, request: ChangeStateRequest) -> ChangeStateResponse:
        lifecycle = self.nodes[name]
        was_active = lifecycle.active
        refused = lifecycle.change(request.transition.id)
        if refused is not None:
            self._node.log.warning("lifecycle: %s", refused)
            return ChangeStateResponse(success=False)
        self._node.log.info("lifecycle: %s is %s", name, lifecycle.state.label)
        if was_active and not lifecycle.active:
            self._stop_work(name)
        return ChangeStateResponse(success=True)

    def _stop_work(self, name: str) -> None:
        for action, server in self._node.action_servers.items():
            if NAV2_WORK.get(action) == name and server.cancel_active():
                self._node.log.info("lifecycle: %s no longer active: cancelling its %s goal", name, action)

    # --- a manager --------------------------------------------------------------------------------

    def _manage(
        self, manager: LifecycleManager, request: ManageLifecycleNodesRequest
    ) -> Deferred[ManageLifecycleNodesResponse]:
        command = request.command
        steps = plan(command, list(manager.nodes))  # ValueError names the commands
        answer: Deferred[ManageLifecycleNodesResponse] = Deferred()
        failures: list[str] = []

        def finish() -> None:
            success = not failures
            managed = managed_state(command, success).label  # as Nav2's manager reports its nodes
            if success:
                self._node.log.info("%s: command %d done: managed nodes %s", manager.name, command, managed)
            else:
                self._node.log.warning(
                    "%s: command %d failed (managed nodes %s): %s",
                    manager.name,
                    command,
                    managed,
                    "; ".join(failures),
                )
            answer.resolve(ManageLifecycleNodesResponse(success=success))

        def next_step(index: int) -> None:
            if index == len(steps):
                finish()
                return
            node, transition, stop_on_failure = steps[index]

            def done(response: ChangeStateResponse | None, error: ServiceError | None) -> None:
                if response is None or not response.success:
                    failures.append(f"{node} refused {transition.label}" + (f" ({error})" if error else ""))
                    if stop_on_failure:
                        finish()
                        return
                next_step(index + 1)

            self._node.call_async(
                CHANGE_STATE,
                change_state_service(node),
                ChangeStateRequest(transition=Transition(id=int(transition), label=transition.label)),
                done,
                timeout_s=CHANGE_STATE_TIMEOUT_S,
            )

        next_step(0)
        return answer


def serve_lifecycle_states(node: Node, service: str) -> StandInLifecycles:
    """The stand-in lifecycles of ``service`` on ``node`` (its servers are held and closed by the node)."""
    return StandInLifecycles(node, service)
