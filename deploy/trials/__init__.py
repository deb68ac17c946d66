"""``zendock trials``: many dockings from random starts on the full distributed stack, measured.

One stack serves ``workers`` robots at once: a single simulator process steps one copy of the room per
robot (namespaces ``r0``, ``r1``, …), and each robot has its own battery, pose, planner and docking
services, exactly the processes the default stack runs. Each trial places its robot at a random
collision-free start (seeded, reproducible), sets the battery just above the low threshold and waits
for ``CHARGING``; the :class:`~deploy.observer.RunObserver` measures it on ground truth. Noise and a
map->odom localisation error are on, as on a real robot.

Modules: :mod:`.records` (options and results), :mod:`.starts` (where trials start),
:mod:`.stack` (the stack file), :mod:`.campaign` (running it), :mod:`.summary` (statistics),
:mod:`.chaos` (fault injection); the histograms are drawn by :func:`deploy.plotting.plot_trial_histograms`.
"""

from deploy.trials.campaign import run_trials
from deploy.trials.records import TrialOptions, TrialResult, TrialsSummary
from deploy.trials.stack import trials_stack
from deploy.trials.starts import START_CLEARANCE_M, lower_bounds, random_starts, reachable_starts
from deploy.trials.summary import combine, summarise, summarise_results

__all__ = [
    "START_CLEARANCE_M",
    "TrialOptions",
    "TrialResult",
    "TrialsSummary",
    "combine",
    "lower_bounds",
    "random_starts",
    "reachable_starts",
    "run_trials",
    "summarise",
    "summarise_results",
    "trials_stack",
]
