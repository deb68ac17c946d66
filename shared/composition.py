"""Composition: several services in one process on one Zenoh session, each on its own node.

ROS 2's answer to the cost of every message crossing a process boundary is the component container;
this is zendock's. Each member is a service's own :class:`~shared.runtime.ServiceSpec`, parsed and built
exactly as ``python -m services.<name>`` does, on a :class:`~shared.node.Node` of its own: its own
parameters, liveliness token (``zendock ps`` and health checks see the same graph), log prefix and
executor thread (callbacks never overlap within a node; nodes do not wait for each other). They share the
session, so a message from one member to another is delivered inside the process, and the members'
subscriptions on one key share one Zenoh subscriber (:mod:`shared.subscriber_hub`); messages to services
elsewhere still go through the router. A callback's exception is contained by its node's executor as
always; anything that stops the process stops the whole group, and the launcher restarts it.
"""

from __future__ import annotations

import logging
import signal
import sys
import threading
from dataclasses import dataclass
from typing import Any

from shared.contracts.enforce import hold_to_contract
from shared.lifecycle_states import serve_lifecycle_states
from shared.node import Node
from shared.parameter_server import attach_parameters
from shared.parameters import ServiceParams
from shared.runtime import ServiceOptions, ServiceSpec, open_session_unless
from shared.waiting import SIGNAL_CHECK_S


@dataclass(frozen=True)
class Member:
    spec: ServiceSpec
    options: ServiceOptions
    params: ServiceParams

    @property
    def label(self) -> str:
        return (
            f"{self.options.namespace}/{self.options.node_name}"
            if self.options.namespace
            else self.options.node_name
        )


def configure_group_logging(members: list[Member]) -> None:
    """One stream; each line prefixed with its node's ``[namespace/name]``, as a service alone writes it."""
    level = min(logging.getLevelName(m.options.log_level) for m in members)
    logging.basicConfig(
        level=level,
        format="%(asctime)s %(levelname)s [%(name)s] %(message)s",
        datefmt="%H:%M:%S",
        stream=sys.stderr,
        force=True,
    )
    for member in members:
        logging.getLogger(member.label).setLevel(member.options.log_level)


def serve_group(members: list[Member], *, install_signal_handlers: bool = True) -> int:
    """Build every member on one session, spin each on its own thread until a signal, close everything.

    The session is the first member's (all members of a group share their connect/listen flags)."""
    if not members:
        raise ValueError("a group needs at least one service")
    configure_group_logging(members)
    log = logging.getLogger("container")
    for prepare in dict.fromkeys(m.spec.prepare for m in members if m.spec.prepare is not None):
        prepare()
    stop = threading.Event()
    if install_signal_handlers:
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, lambda *_: stop.set())
    first = members[0].options
    log.info("connecting to %s: %s", ",".join(first.connect), ", ".join(m.label for m in members))
    started: list[tuple[Member, Node, Any, threading.Thread]] = []
    code = 0
    opened = open_session_unless(first.session_spec(), stop)  # SIGTERM ends it even before the router answers
    if opened is None:
        log.info("stopped before the router answered")
        return 0
    with opened as session:
        try:
            for member in members:
                logger = logging.getLogger(member.label)
                node = Node(
                    member.options.node_name,
                    session,
                    member.options.namespace,
                    use_sim_time=member.params.use_sim_time,
                    logger=logger,
                )
                hold_to_contract(node)
                service = member.spec.build(node, member.params)
                attach_parameters(node, member.params, service)  # closed with the node
                serve_lifecycle_states(node, member.spec.name)  # closed with the node
                node.declare_ready()
                thread = threading.Thread(target=node.spin, name=member.label, daemon=True)
                thread.start()
                started.append((member, node, service, thread))
                logger.info("ready in a group of %d (namespace %r)", len(members), member.options.namespace)
            while not stop.wait(SIGNAL_CHECK_S):
                gone = [m.label for m, _n, _s, t in started if not t.is_alive()]
                if gone:
                    log.error("node %s stopped: stopping the group", ", ".join(gone))
                    code = 1
                    break
        finally:
            for _member, node, _service, _thread in started:
                node.shutdown()
            for member, node, service, thread in reversed(started):
                thread.join(timeout=5.0)
                if service is not None:
                    service.close()
                node.close()
                logging.getLogger(member.label).info("stopped")
    return code
