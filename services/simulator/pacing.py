"""Pacing by the drivers: the world waits, briefly, for a moving robot's late command.

At a high real-time factor on a busy machine the controllers fall behind the simulated clock: a
command computed for sim time ``t`` arrives when the world is already at ``t + 0.5 s``, and the robot
drives blind in between. A lockstep simulator would wait for every controller at every step; this one
waits only when it matters -- while a robot moves on a command older than ``driver_gap_s`` of sim
time, or while its localisation (``map_to_base_link_pose2d``) is older than ``pose_gap_s`` -- and
never longer than ``driver_wait_max_s`` of wall time for the same late input, so a service that died
cannot freeze the world (the ``cmd_vel`` watchdog then stops its robot as usual). The achieved
real-time factor is then what the whole stack sustains, not what the physics alone could do.

The pose matters as much as the command: a controller whose pose is stale holds its robot still,
which stops the pacing on commands, and the world then runs flat out while the robot waits -- the
pose falls further behind and sim-time deadlines (staging, recoveries) expire with nothing done.
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
    #: A robot's pose is late once this old (sim seconds): three periods of the 10 Hz pose.
    pose_gap_s: float = 0.3


@dataclass(frozen=True)
class Driver:
    """One input the world may wait for: its name, when it last arrived, whether it is awaited now.

    A robot's command is awaited while the robot moves; its pose once one has arrived (a world with no
    pose service is never held for one). ``gap_s`` overrides the pacer's ``driver_gap_s``.
    """

    name: str
    last_command_s: float
    moving: bool
    gap_s: float | None = None


class DriverPacer:
    """Decides, before each step, whether the world should wait for a late driver."""

    def __init__(self, params: PacingParams) -> None:
        self.params = params
        self._awaited: tuple[tuple[str, float], ...] = ()
        self._since_wall_s = 0.0
        #: How many times the world waited, and for how long in all (wall seconds).
        self.holds = 0
        self.held_s = 0.0
        #: Wall seconds held, by the kind of input awaited ("cmd_vel" or "pose"; both when both were late).
        self.held_by_kind: dict[str, float] = {}
        self._last_late: tuple[tuple[str, float], ...] = ()

    def hold(self, sim_now_s: float, wall_now_s: float, drivers: Iterable[Driver]) -> bool:
        """True: do not step yet. Call again (after a short sleep) until it says False."""
        gap = self.params.driver_gap_s
        late = tuple(
            (d.name, d.last_command_s) for d in drivers
            if d.moving and sim_now_s - d.last_command_s > (gap if d.gap_s is None else d.gap_s)
        )
        if not late:
            self._awaited = ()
            return False
        if late != self._awaited:  # a new wait: the budget starts again
            self._awaited = late
            self._last_late = late
            self._since_wall_s = wall_now_s
            self.holds += 1
        waited = wall_now_s - self._since_wall_s
        if waited >= self.params.driver_wait_max_s:
            return False  # budget spent on these commands: step on until a new command arrives
        return True

    def note_held(self, seconds: float) -> None:
        seconds = max(0.0, seconds)
        self.held_s += seconds
        # what the wait that just ended was for (``hold`` has already forgotten it: nothing is late now)
        kinds = sorted({"pose" if name.endswith(":pose") else "cmd_vel" for name, _ in self._last_late}) or ["?"]
        kind = "+".join(kinds)
        self.held_by_kind[kind] = self.held_by_kind.get(kind, 0.0) + seconds
