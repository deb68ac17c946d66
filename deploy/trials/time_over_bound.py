"""Where a docking's time over its lower bound goes: the reaction, navigation, glass, detours, the approach.

The lower bound (:mod:`services.planner.lower_bound`) is the shortest collision-free path driven at full
speed, plus the turns it forces at full turning speed. A trial's dock time over that bound splits exactly
into parts, each from the docking states' sim seconds and the ground-truth metres driven in them:

- ``trigger``: from the battery's crossing until the docking service leaves IDLE (the bound has no
  reaction time);
- ``navigation``: driving to the staging pose, less what its own distance would take at full speed:
  slowing for curves and obstacles, turning, waiting for plans, recoveries; less the ``glass`` part;
- ``glass``: the seconds the planner drove under a glass speed limit, less what the metres it drove in
  them would take at full speed (:class:`GlassSlowing`, the planner's own count and its pose track's
  speed; slowing for a curve while under the limit counts here too). Part of navigation, taken out of it;
- ``detour``: the distance driven beyond the bound's path, at full speed;
- ``turns``: less the bound's turns, which the bound makes in place and the robot mostly makes while it
  drives (so this part is never positive: the time the robot saved against the bound's turning);
- ``approach``: perceiving the dock, the final approach and waiting for the charge, less what their
  distance would take at full speed (the approach slows to meet the plate gently by design);
- ``other``: any other state (a retry), the same way.

The parts add up to the dock time less the bound. Pure: no bus, no files.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

#: The speeds the bound is computed at (the robot's limits; passed to the lower-bound tool).
BOUND_MAX_LINEAR_MPS = 0.5
BOUND_MAX_ANGULAR_RADPS = 1.5

TRIGGER_STATE = "TRIGGER"
NAVIGATION_STATE = "NAV_TO_STAGING_POSE"
APPROACH_STATES = ("INITIAL_PERCEPTION", "CONTROLLING", "WAIT_FOR_CHARGE")
#: The parts, in the order a docking goes through them.
PARTS = ("trigger", "navigation", "glass", "detour", "turns", "approach", "other")


@dataclass(frozen=True)
class GlassSlowing:
    """What the planner counted of its driving under a glass speed limit during one docking."""

    seconds: float
    metres: float

    @property
    def over_full_speed_s(self) -> float:
        """The time the limit cost: its seconds less its metres at full speed (0 when not counted)."""
        if not (math.isfinite(self.seconds) and math.isfinite(self.metres)):
            return 0.0
        return self.seconds - self.metres / BOUND_MAX_LINEAR_MPS


@dataclass(frozen=True)
class LowerBound:
    """One start's lower bound and what it is made of."""

    seconds: float
    path_length_m: float
    turn_rad: float
    #: The widest way's narrowest gap (NaN: not given).
    way_width_m: float = math.nan

    @property
    def turn_s(self) -> float:
        return self.turn_rad / BOUND_MAX_ANGULAR_RADPS


def time_over_bound(
    phase_s: Mapping[str, float],
    phase_length_m: Mapping[str, float],
    bound: LowerBound,
    glass: GlassSlowing | None = None,
) -> dict[str, float]:
    """The parts of a docking's time over ``bound`` (see the module doc), from the sim seconds and metres
    driven in each docking state between the trigger and charging and what the planner counted of its glass
    slowing (none: a ``glass`` part of 0); empty without a finite bound."""
    if not (math.isfinite(bound.seconds) and math.isfinite(bound.path_length_m)):
        return {}
    speed = BOUND_MAX_LINEAR_MPS

    def beyond_full_speed(states: list[str]) -> float:
        seconds = sum(phase_s.get(state, 0.0) for state in states)
        metres = sum(phase_length_m.get(state, 0.0) for state in states)
        return seconds - metres / speed

    named = {TRIGGER_STATE, NAVIGATION_STATE, *APPROACH_STATES}
    others = [state for state in phase_s if state not in named]
    driven_m = sum(phase_length_m.values())
    glass_s = glass.over_full_speed_s if glass is not None else 0.0
    parts = {
        "trigger": beyond_full_speed([TRIGGER_STATE]),
        "navigation": beyond_full_speed([NAVIGATION_STATE]) - glass_s,
        "glass": glass_s,
        "detour": (driven_m - bound.path_length_m) / speed,
        "turns": -bound.turn_s,
        "approach": beyond_full_speed(list(APPROACH_STATES)),
        "other": beyond_full_speed(others),
    }
    return {name: round(seconds, 3) for name, seconds in parts.items()}


__all__ = [
    "APPROACH_STATES",
    "BOUND_MAX_ANGULAR_RADPS",
    "BOUND_MAX_LINEAR_MPS",
    "PARTS",
    "GlassSlowing",
    "LowerBound",
    "time_over_bound",
]
