"""Pacing by the drivers: the world waits, briefly, for a moving robot's late command.

At a high real-time factor on a busy machine the controllers fall behind the simulated clock: a
command computed for sim time ``t`` arrives when the world is already at ``t + 0.5 s``, and the robot
drives blind in between. A lockstep simulator would wait for every controller at every step; this one
waits only when it matters -- while a robot moves on a command older than ``driver_gap_s`` of sim
time, or while its localisation (``map_to_base_link_pose2d``) is older than ``pose_gap_s`` -- and
never longer than ``driver_wait_max_s`` of wall time for the same late input (``hold_wait_max_s`` for a
hold a controller announced while it works: a plan, a costmap change), so a service that died
cannot freeze the world (the ``cmd_vel`` watchdog then stops its robot as usual). The achieved
real-time factor is then what the whole stack sustains, not what the physics alone could do.

The pose matters as much as the command: a controller whose pose is stale holds its robot still,
which stops the pacing on commands, and the world then runs flat out while the robot waits -- the
pose falls further behind and sim-time deadlines (staging, recoveries) expire with nothing done.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Annotated

from msgspec import Meta

from shared.models.component import ComponentParams

#: Time the world lost against its wall-clock schedule (held for a late driver, or the machine was busy) is
#: made up by stepping faster than the target, at most this many times the target rate: a user who asks for
#: 3x gets an hour simulated in twenty minutes when the stack can sustain it, and the drivers never see the
#: clock jump (made up at once, the lost time would come back as a burst of steps the controllers cannot
#: follow, and the world would hold for them again).
CATCH_UP_FACTOR = 1.25
#: A schedule this far behind (a suspended machine, a debugger) restarts from now instead of catching up.
CATCH_UP_LIMIT_S = 1.0
#: How long to sleep while holding for a late driver, and at most while waiting for the next step (wall s).
HOLD_SLEEP_S = 0.0005
MAX_SLEEP_S = 0.05


class PacingParams(ComponentParams, frozen=True):
    """``pacing.*``: whether and how long the world waits for late drivers and poses."""

    to_drivers: Annotated[
        bool, Meta(description="wait (briefly) for a moving robot's late command instead of driving it blind")
    ] = True
    to_pose: Annotated[
        bool,
        Meta(description="with to_drivers: also wait (briefly) for a robot's late map_to_base_link_pose2d"),
    ] = True
    #: A moving robot's driver is late once its last command is this old (sim seconds): three periods
    #: of a 20 Hz controller.
    driver_gap_s: Annotated[
        float, Meta(gt=0, description="a moving robot's command older than this (sim) is late")
    ] = 0.15
    #: The longest wait for one late command (wall seconds).
    driver_wait_max_s: Annotated[
        float, Meta(ge=0, description="wait at most this long (wall) for one late command")
    ] = 0.1
    #: The longest wait while every late input is a hold a live service announced (wall seconds).
    hold_wait_max_s: Annotated[
        float,
        Meta(
            ge=0,
            description="wait at most this long (wall) while only announced holds are late: a controller "
            "that said it is at work (a plan, a costmap change) is waited for, not stepped past",
        ),
    ] = 2.0
    #: A robot's pose is late once this old (sim seconds): three periods of the 10 Hz pose.
    pose_gap_s: Annotated[float, Meta(gt=0, description="a robot's pose older than this (sim) is late")] = 0.3
    #: Lockstep: a moving robot's command is late once its own controller's period (from the cadence of its
    #: recent commands) has passed by this factor, rather than after ``driver_gap_s``: the world does not
    #: run on past the step a command answers, whatever the speed-up (0: ``driver_gap_s`` alone).
    lockstep_factor: Annotated[
        float,
        Meta(
            ge=0, description="a moving robot's command is late after this many of its own periods (0: off)"
        ),
    ] = 1.2


class CommandCadence:
    """When a robot's commands arrive (sim time), and so the period its controller runs at: the median of
    its recent intervals. Commands heard within one step count once; a pause longer than
    :data:`CADENCE_BREAK_S` starts the count again (a new controller, or one that paused)."""

    def __init__(self, keep: int = 8) -> None:
        self._keep = keep
        self._intervals: list[float] = []
        self._last_s = -math.inf

    def heard(self, sim_s: float, step_s: float) -> None:
        interval = sim_s - self._last_s
        if interval < step_s / 2.0:
            return  # the same step: one more command for it, not a new period
        self._last_s = sim_s
        if interval > CADENCE_BREAK_S:
            self._intervals.clear()
            return
        self._intervals = [*self._intervals[-(self._keep - 1) :], interval]

    def period_s(self) -> float | None:
        """The controller's period, once three intervals say it; else None."""
        if len(self._intervals) < 3:
            return None
        # statistics.median_high without importing statistics (with fractions and random) at start-up
        return sorted(self._intervals)[len(self._intervals) // 2]

    def gap_s(self, params: PacingParams, step_s: float) -> float | None:
        """How old its last command may grow while it moves: ``lockstep_factor`` periods, at least two
        steps, at most ``driver_gap_s``; None (the pacer's default) when the cadence is not known yet."""
        period = self.period_s()
        if period is None or params.lockstep_factor <= 0.0:
            return None
        return min(params.driver_gap_s, max(2.0 * step_s, params.lockstep_factor * period))


#: Commands further apart than this (sim s) are not one controller's stream.
CADENCE_BREAK_S = 0.5


#: A handoff's hold lapses once the world has run this far past its tick, or past its arrival if it came
#: later (sim seconds): further than any wait lets it run (a driver's gap), so only after the wait ran out
#: of budget.
HOLD_LAPSE_S = 0.5


class HandoffHold:
    """A robot handed from one driver to another (see :class:`shared.messages.PacingHold`): the tick the
    world should not run far past until the robot is driven again, or None.

    A hold is let go by its holder (``hold`` false), by a newer hold, or, ``until_driven``, by a command
    that moves the robot and answers its tick or a later one (the next driver has taken over); such a
    hold that arrives after the robot was already driven on a later tick is stale and ignored. A hold not
    ``until_driven`` is for a holder that drives next itself: the old driver's last commands, still on
    their way, must not end it."""

    def __init__(self) -> None:
        self.tick_s: float | None = None
        self.holder = ""
        self.until_driven = True
        #: Sim time the hold arrived (flat out, one decided on an earlier tick arrives some steps late).
        self._heard_s = -math.inf
        #: Sim time of the last tick a moving command answered.
        self._driven_s = -math.inf

    def heard(self, tick_s: float, holder: str, hold: bool, now_s: float, until_driven: bool = True) -> None:
        """A hold (or a let-go) from ``holder``; a tick from the future counts as now."""
        if not hold:
            if holder == self.holder:
                self.tick_s = None
            return
        tick_s = min(tick_s, now_s)
        if not math.isfinite(tick_s) or (until_driven and tick_s <= self._driven_s):
            return
        # the arrival first: the stepping thread reads the tick (and lapses it) without a lock
        self._heard_s = now_s
        self.holder, self.until_driven = holder, until_driven
        self.tick_s = tick_s

    def current(self, now_s: float) -> float | None:
        """The hold's tick, or None; a hold the world has run :data:`HOLD_LAPSE_S` on since (its wait ran out of
        budget, or nobody will let go: a holder that died) lapses, so that it is waited for once, not again
        each time another input comes late beside it."""
        if self.tick_s is not None and now_s - max(self.tick_s, self._heard_s) > HOLD_LAPSE_S:
            self.tick_s = None
        return self.tick_s

    def driven(self, answered_s: float, moving: bool) -> None:
        """A command answering ``answered_s`` arrived; one that moves the robot ends a hold it answers."""
        if not moving:
            return
        self._driven_s = max(self._driven_s, answered_s)
        if self.tick_s is not None and self.until_driven and answered_s >= self.tick_s:
            self.tick_s = None


@dataclass(frozen=True)
class Driver:
    """One input the world may wait for: its name, when it last arrived, whether it is awaited now.

    A robot's command is awaited while the robot moves, or while its controller says it is still at work on
    an old tick (its stop arrived answering a tick already late); its pose once one has arrived (a world
    with no pose service is never held for one). ``gap_s`` overrides the pacer's ``driver_gap_s``.
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
        #: How many waits ran out of budget, the world stepping on without the late input, and what the
        #: last of them waited for (names and how late, sim seconds).
        self.gave_up = 0
        self.gave_up_on: tuple[tuple[str, float], ...] = ()
        #: The wall seconds that last wait was allowed (a late command's budget, or a hold's).
        self.gave_up_after_s = 0.0
        self._gave_up_current = False

    def hold(self, sim_now_s: float, wall_now_s: float, drivers: Iterable[Driver]) -> bool:
        """True: do not step yet. Call again (after a short sleep) until it says False."""
        gap = self.params.driver_gap_s
        late = tuple(
            (d.name, d.last_command_s)
            for d in drivers
            if d.moving and sim_now_s - d.last_command_s > (gap if d.gap_s is None else d.gap_s)
        )
        if not late:
            self._awaited = ()
            return False
        if late != self._awaited:  # a new wait: the budget starts again
            self._awaited = late
            self._last_late = late
            self._since_wall_s = wall_now_s
            self._gave_up_current = False
            self.holds += 1
        waited = wall_now_s - self._since_wall_s
        budget_s = self._budget_s(late)
        if waited >= budget_s:
            if not self._gave_up_current:
                self._gave_up_current = True
                self.gave_up += 1
                self.gave_up_after_s = budget_s
                self.gave_up_on = tuple((name, sim_now_s - last_s) for name, last_s in late)
            return False  # budget spent on these commands: step on until a new command arrives
        return True

    def _budget_s(self, late: tuple[tuple[str, float], ...]) -> float:
        """How long the world waits for ``late``: an announced hold's budget when nothing else is late (its
        holder said it is at work, and lets go when done; a holder that died is waited for that long once),
        else the budget for a late command or pose."""
        if all(_input_kind(name) == "hold" for name, _ in late):
            return max(self.params.hold_wait_max_s, self.params.driver_wait_max_s)
        return self.params.driver_wait_max_s

    def note_held(self, seconds: float) -> None:
        seconds = max(0.0, seconds)
        self.held_s += seconds
        # what the wait that just ended was for (``hold`` has already forgotten it: nothing is late now)
        kinds = sorted({_input_kind(name) for name, _ in self._last_late}) or ["?"]
        kind = "+".join(kinds)
        self.held_by_kind[kind] = self.held_by_kind.get(kind, 0.0) + seconds


def _input_kind(name: str) -> str:
    """What a driver's name says it is: a robot's pose, a handoff hold, or its commands."""
    suffix = name.rpartition(":")[2] if ":" in name else ""
    return suffix if suffix in ("pose", "hold") else "cmd_vel"


@dataclass(frozen=True)
class Tick:
    """What the stepping loop does now: step, or sleep ``sleep_s``; ``hold_ended``: a wait just ended
    (publish the pacer's counters)."""

    step: bool
    sleep_s: float = 0.0
    hold_ended: bool = False


class StepPacer:
    """Paces steps of ``dt_s`` against the wall clock at ``rtf`` (``"max"``: flat out), holding for late
    drivers with ``drivers`` (None: never). Time lost to a hold or a busy machine is made up at no more than
    :data:`CATCH_UP_FACTOR` times the target rate; more than :data:`CATCH_UP_LIMIT_S` behind, the schedule
    restarts from now.
    """

    def __init__(self, dt_s: float, rtf: float | str, drivers: DriverPacer | None, wall_now_s: float) -> None:
        self.wall_per_step_s = 0.0 if rtf == "max" else dt_s / float(rtf)
        self.drivers = drivers
        #: When the next step is due on the target schedule.
        self._next_wall_s = wall_now_s
        #: When the last step ran: steps are at least ``wall_per_step_s / CATCH_UP_FACTOR`` apart.
        self._last_step_wall_s = -math.inf
        self._held_since_s: float | None = None

    def tick(self, wall_now_s: float, sim_now_s: float, awaited: Callable[[], Iterable[Driver]]) -> Tick:
        """Whether to step now; ``awaited`` lists the inputs the driver pacer may wait for."""
        pacer = self.drivers
        if pacer is not None and pacer.hold(sim_now_s, wall_now_s, awaited()):
            if self._held_since_s is None:
                self._held_since_s = wall_now_s
            return Tick(step=False, sleep_s=HOLD_SLEEP_S)
        hold_ended = False
        if self._held_since_s is not None:
            assert pacer is not None
            pacer.note_held(wall_now_s - self._held_since_s)
            self._held_since_s = None
            hold_ended = True  # the schedule stays: the held time is made up
        if self.wall_per_step_s > 0.0:
            due_s = self._next_wall_s
            if wall_now_s - due_s > CATCH_UP_LIMIT_S:
                due_s = self._next_wall_s = wall_now_s
            due_s = max(due_s, self._last_step_wall_s + self.wall_per_step_s / CATCH_UP_FACTOR)
            if wall_now_s < due_s:
                return Tick(step=False, sleep_s=min(due_s - wall_now_s, MAX_SLEEP_S), hold_ended=hold_ended)
            self._next_wall_s += self.wall_per_step_s
            # When it was due, not when it ran: a late wake-up (sleep overshoot, the interpreter lock) must not
            # push every later step back. At most a period back, so a late step brings no burst after it.
            self._last_step_wall_s = max(due_s, wall_now_s - self.wall_per_step_s)
        return Tick(step=True, hold_ended=hold_ended)


def pacing_stats(pacer: DriverPacer, sim_s: float) -> dict[str, float]:
    """The waits for late drivers as the node's extra counters (``@zendock/stats``)."""
    extra = {
        "pacing_holds": float(pacer.holds),
        "pacing_held_s": pacer.held_s,
        "pacing_gave_up": float(pacer.gave_up),
        "sim_s": sim_s,
    }
    extra.update({f"pacing_held_s_{kind}": s for kind, s in pacer.held_by_kind.items()})
    return extra


def rate_report(sim_s: float, wall_s: float, target: float | str, pacer: DriverPacer | None) -> str:
    """The log line for a real-time factor achieved over ``wall_s`` wall seconds that ran ``sim_s``."""
    achieved = sim_s / max(wall_s, 1e-9)
    waits = ""
    if pacer is not None:
        kinds = ", ".join(f"{kind} {s:.1f} s" for kind, s in sorted(pacer.held_by_kind.items()))
        waits = f"; waited for late drivers {pacer.holds} times, {pacer.held_s:.1f} s in all" + (
            f" ({kinds})" if kinds else ""
        )
    return f"real-time factor {achieved:.1f} over the last {wall_s:.0f} s (target {target}){waits}"
