"""Nav2's lifecycle, as zendock's stand-ins keep it: a node's four states, its transitions, and what a
lifecycle manager's command does to the nodes it manages. Pure: no bus, no clock.

A Nav2 server is a ROS 2 lifecycle node: ``unconfigured``, ``inactive`` (configured, not working),
``active`` (working), ``finalized`` (shut down for good). ``lifecycle_manager_navigation`` and
``lifecycle_manager_localization`` move their nodes together: ``STARTUP`` configures then activates each,
in order; ``PAUSE`` deactivates them in reverse order; ``RESUME`` activates them; ``RESET`` deactivates
and cleans them up; ``SHUTDOWN`` deactivates, cleans up and shuts them down; ``CONFIGURE`` and
``CLEANUP`` are the single steps. A step fails on a node not in the state it starts from (configuring an
active node fails, as in Nav2), and the command stops at the first failure, except ``SHUTDOWN``, which
goes on regardless. zendock's services start active (Nav2's ``autostart``), so a script's
``lifecycleStartup()`` on a running stack is answered ``success: false``, as Nav2's would be.
"""

from __future__ import annotations

from enum import IntEnum

import msgspec


class State(IntEnum):
    """``lifecycle_msgs/msg/State``'s primary states."""

    UNKNOWN = 0
    UNCONFIGURED = 1
    INACTIVE = 2
    ACTIVE = 3
    FINALIZED = 4

    @property
    def label(self) -> str:
        return self.name.lower()


class Transition(IntEnum):
    """``lifecycle_msgs/msg/Transition``'s ids for the transitions a client may ask for."""

    CONFIGURE = 1
    CLEANUP = 2
    ACTIVATE = 3
    DEACTIVATE = 4
    UNCONFIGURED_SHUTDOWN = 5
    INACTIVE_SHUTDOWN = 6
    ACTIVE_SHUTDOWN = 7

    @property
    def label(self) -> str:
        return self.name.lower()


#: Each transition: the state it starts from and the state it ends in.
_EDGES: dict[Transition, tuple[State, State]] = {
    Transition.CONFIGURE: (State.UNCONFIGURED, State.INACTIVE),
    Transition.CLEANUP: (State.INACTIVE, State.UNCONFIGURED),
    Transition.ACTIVATE: (State.INACTIVE, State.ACTIVE),
    Transition.DEACTIVATE: (State.ACTIVE, State.INACTIVE),
    Transition.UNCONFIGURED_SHUTDOWN: (State.UNCONFIGURED, State.FINALIZED),
    Transition.INACTIVE_SHUTDOWN: (State.INACTIVE, State.FINALIZED),
    Transition.ACTIVE_SHUTDOWN: (State.ACTIVE, State.FINALIZED),
}


class NodeLifecycle:
    """One stand-in node's state; starts ``active`` (zendock's services start working)."""

    def __init__(self, name: str, state: State = State.ACTIVE) -> None:
        self.name = name
        self.state = state

    @property
    def active(self) -> bool:
        return self.state == State.ACTIVE

    def change(self, transition: int) -> str | None:
        """Take ``transition`` (a :class:`Transition` id); None when done, else why it was refused."""
        try:
            step = Transition(transition)
        except ValueError:
            return f"{self.name}: no transition {transition} (ids {[int(t) for t in Transition]})"
        start, end = _EDGES[step]
        if self.state != start:
            return f"{self.name}: cannot {step.label} from {self.state.label} (it starts from {start.label})"
        self.state = end
        return None


class Command(IntEnum):
    """``nav2_msgs/srv/ManageLifecycleNodes``' commands."""

    STARTUP = 0
    PAUSE = 1
    RESUME = 2
    RESET = 3
    SHUTDOWN = 4
    CONFIGURE = 5
    CLEANUP = 6


class Step(msgspec.Struct, frozen=True):
    """One pass over a manager's nodes: the transition each takes, in reverse order or not, and whether
    a refusal stops the command (a shutdown carries on)."""

    transition: Transition
    reverse: bool = False
    stop_on_failure: bool = True


#: What each command does, pass by pass, as Nav2's lifecycle manager: bring-up in order, take-down in
#: reverse order. A shutdown's passes take whichever shutdown transition starts from the node's state.
PLANS: dict[Command, tuple[Step, ...]] = {
    Command.STARTUP: (Step(Transition.CONFIGURE), Step(Transition.ACTIVATE)),
    Command.PAUSE: (Step(Transition.DEACTIVATE, reverse=True),),
    Command.RESUME: (Step(Transition.ACTIVATE),),
    Command.RESET: (Step(Transition.DEACTIVATE, reverse=True), Step(Transition.CLEANUP, reverse=True)),
    Command.SHUTDOWN: (
        Step(Transition.DEACTIVATE, reverse=True, stop_on_failure=False),
        Step(Transition.CLEANUP, reverse=True, stop_on_failure=False),
        Step(Transition.UNCONFIGURED_SHUTDOWN, reverse=True, stop_on_failure=False),
    ),
    Command.CONFIGURE: (Step(Transition.CONFIGURE),),
    Command.CLEANUP: (Step(Transition.CLEANUP, reverse=True),),
}


def plan(command: int, nodes: list[str]) -> list[tuple[str, Transition, bool]]:
    """The transitions ``command`` asks of ``nodes`` (Nav2's order), one ``(node, transition,
    stop_on_failure)`` each. Raises ``ValueError`` naming the commands for an unknown one."""
    try:
        steps = PLANS[Command(command)]
    except ValueError:
        known = ", ".join(f"{c.name} {int(c)}" for c in Command)
        raise ValueError(f"no lifecycle command {command} (commands: {known})") from None
    return [
        (node, step.transition, step.stop_on_failure)
        for step in steps
        for node in (reversed(nodes) if step.reverse else nodes)
    ]


def managed_state(command: int, success: bool) -> State:
    """The manager's view of its nodes after ``command`` (``unknown`` after a failure, as Nav2's)."""
    if not success and Command(command) != Command.SHUTDOWN:
        return State.UNKNOWN
    return {
        Command.STARTUP: State.ACTIVE,
        Command.RESUME: State.ACTIVE,
        Command.PAUSE: State.INACTIVE,
        Command.CONFIGURE: State.INACTIVE,
        Command.RESET: State.UNCONFIGURED,
        Command.CLEANUP: State.UNCONFIGURED,
        Command.SHUTDOWN: State.FINALIZED,
    }[Command(command)]
