"""What a trials campaign is asked to do, and what each trial and the campaign measured."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from deploy.paths import RUNS_DIR
from deploy.replacements import Replacement
from shared.controllers import DEFAULT_CONTROLLER, ControllerName, DetectorName

T = TypeVar("T")


@dataclass(frozen=True)
class Shard:
    """The ``index``-th (1-based) of ``count`` disjoint slices of a campaign's trials.

    The campaign's trials are numbered across its worlds, in order: a world's trial ``i`` (0-based, in
    its order of starts) is the campaign's trial ``first + i``, and belongs to shard ``(first + i) % count
    + 1``. Round robin, so every shard gets starts from the whole room rather than one stretch of the list,
    a campaign of one trial in each of many rooms (``generated:KIND``) deals its rooms out to the shards,
    and the union of the shards is exactly the unsharded campaign, trial indices included.
    """

    index: int = 1
    count: int = 1
    #: The campaign's number for this world's first trial: the trials of the worlds before it.
    first: int = 0

    def __post_init__(self) -> None:
        if not (self.count >= 1 and 1 <= self.index <= self.count):
            raise ValueError(f"shard {self.index}/{self.count}: K/N needs 1 <= K <= N")

    @classmethod
    def parse(cls, text: str) -> Shard:
        """``K/N`` (as ``--shard`` takes it)."""
        try:
            index, count = (int(part) for part in text.split("/"))
        except ValueError:
            raise ValueError(f"shard {text!r}: expected K/N, e.g. 1/4") from None
        return cls(index, count)

    def owns(self, trial_index: int) -> bool:
        """Whether this world's trial ``trial_index`` is this shard's."""
        return (self.first + trial_index) % self.count == self.index - 1

    def in_worlds(self, trials_per_world: Sequence[int]) -> list[Shard | None]:
        """This shard placed in each world of a campaign that runs ``trials_per_world`` trials in its
        worlds, in order; None for a world none of whose trials is this shard's (run nothing there)."""
        placed: list[Shard | None] = []
        first = 0
        for n in trials_per_world:
            shard = Shard(self.index, self.count, first)
            placed.append(shard if any(shard.owns(i) for i in range(min(n, self.count))) else None)
            first += n
        return placed

    def select(self, items: Sequence[T]) -> list[tuple[int, T]]:
        """This shard's items of the whole campaign's list, each with its index in the whole list."""
        return [(i, item) for i, item in enumerate(items) if self.owns(i)]

    def __str__(self) -> str:
        return f"{self.index}/{self.count}"


@dataclass(frozen=True)
class TrialOptions:
    world: Path
    n: int = 10
    controller: ControllerName = DEFAULT_CONTROLLER
    #: How the robot finds its dock: ``aruco`` (camera images through the perception service) or
    #: ``synthetic`` (the simulator's true dock pose plus noise).
    detector: DetectorName = "aruco"
    #: Where trials start: ``room`` (anywhere reachable, away from the dock) or ``beacon`` (within 2 m in
    #: front of the dock, where infrared docking can start).
    starts: str = "room"
    seed: int = 0
    rtf: str = "8"
    workers: int = 1
    timeout_sim_s: float = 240.0
    localisation_error: tuple[float, float, float] = (0.03, -0.02, 0.02)
    battery_start: float = 0.255
    drain_scale: float = 20.0
    runs_dir: Path = RUNS_DIR
    #: Fault injection: every ``chaos_period_s`` wall seconds on average, kill -9 a random robot service
    #: (battery, pose, planner or docking; never the simulator) and let the launcher restart it. 0: off.
    chaos_period_s: float = 0.0
    #: A warm standby of each robot service (``--standby``, :mod:`deploy.standby`): restarts start from it.
    standby: bool = False
    #: Each robot's services in one process (``zendock container``): ``all`` of them, or only the ``light``
    #: ones (battery and pose), the planner, perception and docking each keeping a process; "" for none.
    compose: str = ""
    #: Which slice of the campaign this run does (``zendock trials --shard K/N``; merge with ``trials merge``).
    shard: Shard = Shard()
    #: ``--service NAME=COMMAND``: a user's program in place of zendock's service in every robot's copy.
    replacements: tuple[Replacement, ...] = ()


@dataclass
class TrialResult:
    index: int
    robot: str
    start: tuple[float, float, float]
    docked: bool
    charging: bool
    dock_time_s: float
    lateral_error_m: float
    yaw_error_rad: float
    collisions: int
    path_length_m: float
    lower_bound_s: float = math.nan
    #: The widest way's narrowest gap from where docking began to the dock, glass solid (the lower-bound
    #: tool's, :mod:`services.planner.way_width`; NaN: no bound computed).
    way_width_m: float = math.nan
    wall_s: float = 0.0
    sim_s: float = 0.0
    #: The planner's glass memory after the trial (see :mod:`deploy.glass_report`; NaN: none written yet).
    false_glass_cells: float = math.nan
    glass_coverage: float = math.nan
    #: Panes the sonar heard during the trial (an echo came from them), and how many of those carry a mark.
    panes_heard: int = 0
    panes_found: int = 0
    #: Sim seconds from the trigger to charging in each docking state (see ``RunRecord.phase_durations``).
    phase_s: dict[str, float] = field(default_factory=dict)
    #: The robot's ground-truth speed as its contacts mated (see ``RunRecord.arrival_speed_mps``).
    arrival_speed_mps: float = math.nan
    #: It charged, but met the plate faster than its contact speed limit: a failed trial.
    too_fast: bool = False
    #: Sim seconds the planner drove under a glass speed limit during the trial, and the metres it drove in
    #: them (NaN: not counted).
    glass_slowed_s: float = math.nan
    glass_slowed_m: float = math.nan
    #: Where the dock time over the lower bound went, in sim seconds (see
    #: :mod:`deploy.trials.time_over_bound`; empty without a bound or a charge).
    over_bound_s: dict[str, float] = field(default_factory=dict)
    #: What each collision touched and where, in order: ``{"kind": "glass", "x": ..., "y": ...}`` (map frame,
    #: metres; kind as the simulator's ``collisions`` key gives it).
    collided: list[dict[str, Any]] = field(default_factory=list)
    #: The closest the robot's footprint came to a pane during the trial, on ground truth (metres, 0 when it
    #: touched, at most 1; NaN: the world has no glass), and the pane point nearest then (see
    #: :mod:`deploy.trials.glass_clearance`).
    glass_clearance_m: float = math.nan
    glass_closest_xy: list[float] = field(default_factory=list)


#: A campaign's figures as its JSON line and its summary table give them, in order.
HEADLINE_KEYS = (
    "n",
    "successes",
    "success_rate",
    "median_dock_time_s",
    "median_lower_bound_s",
    "median_time_ratio",
    "median_lateral_error_m",
    "p95_lateral_error_m",
    "median_yaw_error_rad",
    "median_arrival_speed_mps",
    "max_arrival_speed_mps",
    "collisions",
    "wall_s",
    "sim_s",
    "achieved_rtf",
    "median_false_glass_cells",
    "p95_false_glass_cells",
    "median_glass_coverage",
    "heard_panes_found",
    "near_glass_trials",
    "p05_glass_clearance_m",
)


@dataclass
class TrialsSummary:
    n: int
    successes: int
    success_rate: float
    median_dock_time_s: float
    median_lower_bound_s: float
    #: Median over docked trials of each trial's own dock time over its own lower bound.
    median_time_ratio: float
    median_lateral_error_m: float
    p95_lateral_error_m: float
    median_yaw_error_rad: float
    collisions: int
    wall_s: float
    sim_s: float
    controller: str = ""
    world: str = ""
    #: Sim seconds the simulator's clock advanced per wall second while the trials ran (what the whole
    #: stack sustained, waits for late drivers included; NaN when not measured).
    achieved_rtf: float = math.nan
    peak_rss_mb: dict[str, float] = field(default_factory=dict)
    #: CPU seconds each service used per simulated second while the trials ran (the stack's start-up left
    #: out): where a faster-than-real-time run goes.
    cpu_s_per_sim_s: dict[str, float] = field(default_factory=dict)
    chaos: dict[str, Any] = field(default_factory=dict)
    #: Glass memory against the world's panes, over every trial (see :mod:`deploy.glass_report`).
    median_false_glass_cells: float = math.nan
    p95_false_glass_cells: float = math.nan
    median_glass_coverage: float = math.nan
    #: Of the panes the sonar heard, over every trial, the share the glass memory marked (NaN: none heard).
    heard_panes_found: float = math.nan
    #: Trials whose footprint came within ``NEAR_GLASS_M`` of a pane (touches included), and the 5th
    #: percentile of the trials' closest passes (see :mod:`deploy.trials.glass_clearance`; 0 and NaN in a
    #: world without glass): the risk of touching glass, measured on every pass and not only the rare touch.
    near_glass_trials: int = 0
    p05_glass_clearance_m: float = math.nan
    #: Each replaced service and the command that ran in its place (``--service``): whose figures these are.
    replaced_services: dict[str, str] = field(default_factory=dict)
    #: Where the time to dock goes: per docking state, the median over docked trials of its sim seconds
    #: (0 for a trial that never entered it); the medians need not add up to the median dock time.
    median_phase_s: dict[str, float] = field(default_factory=dict)
    #: How fast the robots met their docks: median and fastest ground-truth speed as the contacts mated, over
    #: every mating (a trial that met the plate too fast counts here, and as a failure).
    median_arrival_speed_mps: float = math.nan
    max_arrival_speed_mps: float = math.nan
    #: Median over docked trials of the sim seconds driven under a glass speed limit (part of navigation).
    median_glass_slowed_s: float = math.nan
    #: Where the time over the lower bound goes: per part, the median over docked trials with a bound
    #: (see :mod:`deploy.trials.time_over_bound`); the medians need not add up.
    median_over_bound_s: dict[str, float] = field(default_factory=dict)

    def headline(self) -> dict[str, Any]:
        keys = HEADLINE_KEYS
        line = {k: getattr(self, k) for k in keys}
        if self.median_phase_s:
            line["median_phase_s"] = dict(self.median_phase_s)
        if self.median_over_bound_s:
            line["median_over_bound_s"] = dict(self.median_over_bound_s)
        if self.replaced_services:
            line["replaced_services"] = dict(self.replaced_services)
        return line
