"""What the long commands say while they run: the demo's phases, a dock's approach, a campaign's count.

Pure: text from numbers, no bus, no clock (the caller passes the times), so tests pin each line. Where a
line goes and how often is the command's choice (:func:`progress_period_s`): every couple of seconds on
a terminal, rarely and on stderr when stdout is a pipe or ``--json`` keeps it for the report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TextIO

#: A terminal gets a line this often; a pipe, a log file or ``--json`` (on stderr) this often.
TERMINAL_PERIOD_S = 2.0
QUIET_PERIOD_S = 10.0
#: Without a terminal, ``zendock trials`` prints a line every this many trials (and after the last).
TRIALS_PER_LINE = 10


def is_terminal(stream: TextIO) -> bool:
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())


def progress_period_s(interactive: bool) -> float:
    return TERMINAL_PERIOD_S if interactive else QUIET_PERIOD_S


@dataclass
class Throttle:
    """True at most once every ``period_s`` (the first call is always True)."""

    period_s: float
    _last: float = -math.inf

    def due(self, now_s: float) -> bool:
        if now_s - self._last < self.period_s:
            return False
        self._last = now_s
        return True


def distance_text(distance_m: float | None) -> str:
    if distance_m is None or not math.isfinite(distance_m):
        return "distance to dock unknown"
    return f"{distance_m:.2f} m to dock"


def demo_line(
    *,
    sim_s: float,
    battery: float | None,
    trigger_s: float | None,
    docking_state: str,
    distance_m: float | None,
    trigger_below: float = 0.25,
) -> str:
    """One demo progress line: before the trigger the battery running down, after it the approach."""
    if trigger_s is None:
        charge = f"{100 * battery:.1f} %" if battery is not None and math.isfinite(battery) else "unknown"
        return f"waiting for the low-battery trigger ({100 * trigger_below:.0f} %): battery {charge}, sim {sim_s:.1f} s"
    state = docking_state or "starting"
    return f"docking: {state}, {distance_text(distance_m)}, sim {sim_s:.1f} s (trigger +{sim_s - trigger_s:.1f} s)"


def dock_line(*, docking_time_s: float, state: str, retries: int, distance_m: float | None) -> str:
    """One ``zendock dock`` line: the action's clock, its phase, retries, the distance from the pose."""
    retry = f"  (retry {retries})" if retries else ""
    known = distance_m is not None and math.isfinite(distance_m)
    distance = f"  {distance_m:6.2f} m to the dock" if known else ""
    return f"{docking_time_s:7.1f} s  {state}{retry}{distance}"


def eta_text(done: int, total: int, elapsed_s: float) -> str:
    """The time left at the pace so far ("?" before the first result)."""
    if done <= 0:
        return "?"
    left_s = elapsed_s / done * (total - done)
    minutes, seconds = divmod(int(round(left_s)), 60)
    return f"{minutes}:{seconds:02d}" if minutes < 60 else f"{minutes // 60}h{minutes % 60:02d}m"


def trials_line(*, world: str, done: int, total: int, successes: int, elapsed_s: float) -> str:
    """The plain campaign line printed without a terminal: ``trials seed_room: 10/50, 10 docked, ETA 6:40``."""
    eta = f", ETA {eta_text(done, total, elapsed_s)}" if done < total else f", done in {elapsed_s:.0f} s"
    return f"trials {world}: {done}/{total}, {successes} docked{eta}"
