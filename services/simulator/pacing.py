"""Pacing by the drivers: the world waits, briefly, for a moving robot's late command.

At a high real-time factor on a busy machine the controllers fall behind the simulated clock: a
command computed for sim time ``t`` arrives when the world is already at ``t + 0.5 s``, and the robot
drives blind in between. A lockstep simulator would wait for every controller at every step; this one
waits only when it matters -- while a robot moves on a command older than ``driver_gap_s`` of sim
time -- and never longer than ``driver_wait_max_s`` of wall time for the same command, so a driver
that died cannot freeze the world (the ``cmd_vel`` watchdog then stops its robot as usual). The
achieved real-time factor is then what the whole stack sustains, not what the physics alone could do.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass


@dataclass(frozen=True)
class PacingParams:
    #: A moving robot's driver is late once its last command is this old (sim seconds): three periods
    #: of a 20 Hz controller.
    driver_gap_s: float = 0.15
    #: The longest wait for one late command (wall seconds).
    driver_wait_max_s: float = 0.1


@dataclass(frozen=True)
class Driver:
    """What the pacer needs of one robot: who drives it, when it was last commanded, whether it moves."""

    name: str
    last_command_s: float
    moving: bool


class DriverPacer:
    """Decides, before each step, whether the world should wait for a late driver."""

    def __init__(self, params: PacingParams) -> None:
        self.params = params
        self._awaited: tuple[tuple[str, float], ...] = ()
        self._since_wall_s = 0.0
        #: How many times the world waited, and for how long in all (wall seconds).
        self.holds = 0
        self.held_s = 0.0

    def hold(self, sim_now_s: float, wall_now_s: float, drivers: Iterable[Driver]) -> bool:
        """True: do not step yet. Call again (after a short sleep) until it says False."""
        late = tuple(
            (d.name, d.last_command_s) for d in drivers if d.moving and sim_now_s - d.last_command_s > self.params.driver_gap_s
        )
        if not late:
            self._awaited = ()
            return False
        if late != self._awaited:  # a new wait: the budget starts again
            self._awaited = late
            self._since_wall_s = wall_now_s
            self.holds += 1
        waited = wall_now_s - self._since_wall_s
        if waited >= self.params.driver_wait_max_s:
            return False  # budget spent on these commands: step on until a new command arrives
        return True

    def note_held(self, seconds: float) -> None:
        self.held_s += max(0.0, seconds)
