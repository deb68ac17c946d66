"""zendock's launcher: a Compose-like stack file, supervised processes, and a Python API for tests.

Stack file (``deploy/stack.yaml``; see :mod:`deploy.launcher.stack_file`)::

    name: zendock                      # project name: state under .zendock/<name>/
    namespace: ""                      # every service's ZENDOCK_NAMESPACE (a service's is relative to it)
    zenoh: {connect: ["${ZENOH_CONNECT:-tcp/127.0.0.1:7447}"]}   # every service's ZENDOCK_CONNECT
    # zenoh.config: a Zenoh json5 file for the launcher's own (health-check) session, e.g. credentials
    services:
      router: {command: [zendock, router, --listen, "${ZENOH_LISTEN:-tcp/127.0.0.1:7447}"]}
      simulator:
        command: [python, -m, services.simulator]
        depends_on: {router: {condition: service_started}}
        restart: on-failure            # no | always | on-failure[:max] | unless-stopped
        healthcheck: {liveliness: true, timeout: 5s}
        stop_grace_period: 5s

Python API (what integration and end-to-end tests use)::

    from deploy.launcher import Launcher, free_endpoint, load_stack

    endpoint = free_endpoint()
    stack = load_stack("deploy/stack.yaml", env={"ZENOH_LISTEN": endpoint, "ZENOH_CONNECT": endpoint})
    with Launcher(stack, project_dir=tmp_path, namespace="t1", services=["simulator"]) as stack_handle:
        stack_handle.wait_healthy(timeout_s=20)
        stack_handle.ps()                       # [ServiceStatus(name, state, pid, restarts, health, ...)]
        stack_handle.kill("simulator")          # SIGKILL the group; the restart policy applies
        stack_handle.stop("simulator"); stack_handle.start("simulator"); stack_handle.restart("simulator")
        stack_handle.logs("simulator")          # the lines it printed
        stack_handle.wait_state("simulator", "running", timeout_s=10)
        stack_handle.wait_until(lambda st: st["simulator"].restarts == 1, timeout_s=10, what="a restart")
    # leaving the block stops everything, even when the body raised

``Launcher(stack, services=(), profiles=(), project_dir=None, project_name=None, working_dir=None,
namespace=None, connect=None, environment=None, backoff=None, output=None)``: ``namespace``/``connect``
override the stack's (and so every service's ``ZENDOCK_NAMESPACE``/``ZENDOCK_CONNECT`` and the health
checker's endpoints); ``environment`` is added to every service's environment; ``backoff`` sets the restart
delays (:class:`Backoff`); ``output`` is a text stream receiving all output with ``name |`` prefixes.
Waits raise :class:`StackNotReady` (a ``TimeoutError``) whose message lists every service's status.

Command line: ``zendock up [-f FILE] [-d] [--wait] [--profile P] [SERVICE...]``, ``down``, ``ps [--json]``,
``logs [-f] [--tail N] [SERVICE...]``, ``start|stop|restart|kill SERVICE...``, ``config``, ``router``
(see :mod:`deploy.commands`). Runtime state lives in ``.zendock/<project>/`` (:mod:`deploy.launcher.runtime`).
"""

from deploy.launcher.api import Launcher, StackNotReady, free_endpoint, free_tcp_port, is_ready
from deploy.launcher.restart import Backoff, RestartPolicy
from deploy.launcher.stack_file import Stack, load_stack
from deploy.launcher.status import ServiceStatus

__all__ = [
    "Backoff",
    "Launcher",
    "RestartPolicy",
    "ServiceStatus",
    "Stack",
    "StackNotReady",
    "free_endpoint",
    "free_tcp_port",
    "is_ready",
    "load_stack",
]
