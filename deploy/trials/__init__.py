"""``zendock trials``: many dockings from random starts on the full distributed stack, measured
(see :mod:`.campaign` for how a campaign runs).

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
