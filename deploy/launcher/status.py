"""What ``ps`` reports about a service, and the phases a service goes through."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from datetime import UTC, datetime
from enum import StrEnum
from typing import Any


class Phase(StrEnum):
    """The supervisor's view of a service.

    ``waiting``: for its dependencies before a (re)start; ``running``; ``restarting``: exited, next start
    after a backoff delay; ``exited``: ended by itself (or its dependencies failed) and stays down;
    ``stopped``: stopped by the user, or not started yet.
    """

    WAITING = "waiting"
    RUNNING = "running"
    RESTARTING = "restarting"
    EXITED = "exited"
    STOPPED = "stopped"


@dataclass(frozen=True)
class ServiceStatus:
    name: str
    state: str
    pid: int | None
    restarts: int
    health: str
    phase: str = "stopped"
    exit_code: int | None = None
    #: Human-readable: "waiting for router (service_healthy)", "restarting in 2s", "exited with code 1".
    detail: str = ""
    starts: int = 0
    uptime_s: float | None = None
    #: Wall-clock time (epoch seconds) the current process was launched.
    started_at: float | None = None
    pid_create_time: float | None = None
    #: A composed group's services (one process: they start, crash and restart together); empty otherwise.
    members: list[str] = field(default_factory=list)
    #: The namespace the service runs in (a fleet's robot: ``r1``; "" for the stack's root).
    namespace: str = ""
    #: After a restart, why the run before ended: "exited with code 3: <the line that says why>".
    last_exit: str = ""
    #: The warm standby a restart would fork (``--standby``): "ready", "importing", or "" for none.
    standby: str = ""

    def ps_json(self) -> dict[str, Any]:
        """Exactly the keys ``zendock ps --json`` promises, as ``docker compose ps --format json`` users
        expect them: ``exit_code`` of the last run (null while the first run lasts), ``started_at`` of the
        current process (ISO 8601, UTC; null while no process runs)."""
        started_at = (
            datetime.fromtimestamp(self.started_at, tz=UTC).isoformat(timespec="milliseconds")
            if self.started_at is not None
            else None
        )
        return {
            "name": self.name,
            "state": self.state,
            "pid": self.pid,
            "restarts": self.restarts,
            "health": self.health,
            "exit_code": self.exit_code,
            "started_at": started_at,
            "members": list(self.members),
            "namespace": self.namespace,
        }

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ServiceStatus:
        known = {key: data[key] for key in cls.__dataclass_fields__ if key in data}
        return cls(**known)


def public_state(phase: Phase, starts: int) -> str:
    """The ``state`` of ``zendock ps --json``: running, restarting, exited or stopped. A service waiting for
    its dependencies shows as ``stopped`` before its first start and as ``restarting`` between two runs; its
    ``detail`` says which dependency it waits for."""
    if phase is Phase.WAITING:
        return "restarting" if starts else "stopped"
    return phase.value


def dependency_failed_detail(dependency: str, what: str, condition: str) -> str:
    """A service's detail when it cannot start because ``dependency`` ended (``what``: how it ended)."""
    return f"dependency {dependency} {what} ({condition} not met)"


def failed_dependency(detail: str) -> str | None:
    """The dependency a :func:`dependency_failed_detail` names; None for any other detail."""
    if not detail.startswith("dependency "):
        return None
    name = detail[len("dependency ") :].split(" ", 1)[0]
    return name or None
