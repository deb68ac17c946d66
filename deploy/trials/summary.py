"""Statistics of a set of trials: one world's, or a campaign's across worlds."""

from __future__ import annotations

import math

from deploy.percentiles import median, percentile
from deploy.replacements import replacements_report
from deploy.trials.chaos import combine_chaos
from deploy.trials.glass_clearance import NEAR_GLASS_M
from deploy.trials.records import TrialOptions, TrialResult, TrialsSummary
from deploy.trials.time_over_bound import PARTS
from shared.world import World


def summarise(
    results: list[TrialResult], wall_s: float, options: TrialOptions, world: World
) -> TrialsSummary:
    summary = summarise_results(results, wall_s, options.controller, world.name)
    summary.replaced_services = replacements_report(options.replacements)
    return summary


def summarise_results(
    results: list[TrialResult], wall_s: float, controller: str, world_name: str
) -> TrialsSummary:
    """The summary of any set of trials: one world's, or a campaign's across worlds."""
    ok = [r for r in results if r.docked]
    false_glass = [r.false_glass_cells for r in results if math.isfinite(r.false_glass_cells)]
    coverage = [r.glass_coverage for r in results if math.isfinite(r.glass_coverage)]
    bounded = [r for r in ok if math.isfinite(r.lower_bound_s) and r.lower_bound_s > 0]
    # every mating counts, the ones too fast to be a docking above all
    arrivals = [r.arrival_speed_mps for r in results if math.isfinite(r.arrival_speed_mps)]
    clearances = [r.glass_clearance_m for r in results if math.isfinite(r.glass_clearance_m)]
    return TrialsSummary(
        n=len(results),
        successes=len(ok),
        success_rate=_share(len(ok), len(results)),
        median_dock_time_s=median([r.dock_time_s for r in ok]),
        median_lower_bound_s=median([r.lower_bound_s for r in bounded]),
        median_time_ratio=median([r.dock_time_s / r.lower_bound_s for r in bounded]),
        median_lateral_error_m=median([r.lateral_error_m for r in ok]),
        p95_lateral_error_m=percentile([r.lateral_error_m for r in ok], 0.95),
        median_yaw_error_rad=median([r.yaw_error_rad for r in ok]),
        collisions=sum(r.collisions for r in results),
        wall_s=wall_s,
        sim_s=sum(r.sim_s for r in results if math.isfinite(r.sim_s)),
        controller=controller,
        world=world_name,
        median_false_glass_cells=median(false_glass),
        p95_false_glass_cells=percentile(false_glass, 0.95),
        median_glass_coverage=median(coverage),
        heard_panes_found=_share(sum(r.panes_found for r in results), sum(r.panes_heard for r in results)),
        near_glass_trials=sum(1 for c in clearances if c < NEAR_GLASS_M),
        p05_glass_clearance_m=percentile(clearances, 0.05),
        median_phase_s=median_phases([r.phase_s for r in ok]),
        median_arrival_speed_mps=median(arrivals),
        max_arrival_speed_mps=max(arrivals) if arrivals else math.nan,
        median_glass_slowed_s=median([r.glass_slowed_s for r in ok if math.isfinite(r.glass_slowed_s)]),
        median_over_bound_s=median_over_bound([r.over_bound_s for r in ok if r.over_bound_s]),
    )


def _share(part: int, whole: int) -> float:
    """``part / whole``, NaN when there is no whole."""
    return part / whole if whole else math.nan


def median_phases(per_trial: list[dict[str, float]]) -> dict[str, float]:
    """Each docking state's median sim seconds over the trials, in the order the states first came."""
    names = list(dict.fromkeys(name for phases in per_trial for name in phases))
    return {name: round(median([phases.get(name, 0.0) for phases in per_trial]), 2) for name in names}


def median_over_bound(per_trial: list[dict[str, float]]) -> dict[str, float]:
    """Each part's median sim seconds over the trials, in the parts' own order."""
    if not per_trial:
        return {}
    return {part: round(median([parts.get(part, 0.0) for parts in per_trial]), 2) for part in PARTS}


def combine(per_world: list[tuple[TrialsSummary, list[TrialResult]]], controller: str) -> TrialsSummary:
    """One summary over several worlds' trials: medians over every trial, not medians of medians."""
    results = [r for _, rs in per_world for r in rs]
    wall_s = sum(s.wall_s for s, _ in per_world)
    summary = summarise_results(results, wall_s, controller, ", ".join(s.world for s, _ in per_world))
    rates = [(s.achieved_rtf, s.wall_s) for s, _ in per_world if math.isfinite(s.achieved_rtf)]
    if rates:  # weighted by each world's wall time: the rate of the campaign as a whole
        summary.achieved_rtf = round(sum(r * w for r, w in rates) / max(sum(w for _, w in rates), 1e-9), 2)
    for s, _ in per_world:
        for name, mb in s.peak_rss_mb.items():
            summary.peak_rss_mb[name] = max(mb, summary.peak_rss_mb.get(name, 0.0))
    summary.cpu_s_per_sim_s = _weighted_by_sim_time([(s.cpu_s_per_sim_s, s.sim_s) for s, _ in per_world])
    for s, _ in per_world:  # the same options for every world of a campaign
        summary.replaced_services.update(s.replaced_services)
    chaos = [s.chaos for s, _ in per_world if s.chaos]
    if chaos:
        summary.chaos = combine_chaos(chaos)
    return summary


def _weighted_by_sim_time(rates: list[tuple[dict[str, float], float]]) -> dict[str, float]:
    """Each service's CPU per simulated second over several runs: their rates weighted by sim seconds."""
    totals: dict[str, float] = {}
    sim_s: dict[str, float] = {}
    for per_service, seconds in rates:
        for name, rate in per_service.items():
            totals[name] = totals.get(name, 0.0) + rate * seconds
            sim_s[name] = sim_s.get(name, 0.0) + seconds
    return {name: round(totals[name] / sim_s[name], 4) for name in sorted(totals) if sim_s[name] > 0}


def summary_reasons(summary: TrialsSummary) -> dict[str, str]:
    """Why a summary's measures may be missing (for :func:`deploy.strict_json.dumps`)."""
    none_docked = "no trial docked" if summary.successes == 0 else ""
    return {
        "median_dock_time_s": none_docked or "not measured",
        "median_lateral_error_m": none_docked or "not measured",
        "p95_lateral_error_m": none_docked or "not measured",
        "median_yaw_error_rad": none_docked or "not measured",
        "median_arrival_speed_mps": none_docked or "no ground-truth track when the contacts mated",
        "max_arrival_speed_mps": none_docked or "no ground-truth track when the contacts mated",
        "arrival_speed_mps": "the contacts never mated, or no ground-truth track then",
        "median_lower_bound_s": none_docked
        or "no docked trial has a lower bound (see errors in trials.json)",
        "median_time_ratio": none_docked or "no docked trial has a lower bound (see errors in trials.json)",
        "success_rate": "no trials",
        "achieved_rtf": "the simulator's clock did not answer",
        "lower_bound_s": "no lower bound for this trial's start (see errors in trials.json)",
        "way_width_m": "no lower bound for this trial's start (see errors in trials.json)",
        "dock_time_s": "the trial did not charge",
        "lateral_error_m": "the contacts never touched",
        "yaw_error_rad": "the contacts never touched",
        "sim_s": "the trial never triggered docking",
        "median_glass_slowed_s": none_docked or "no planner counted its glass slowdowns",
        "glass_slowed_s": "the planner does not count its glass slowdowns (replaced?)",
        "median_false_glass_cells": "no planner wrote its glass memory",
        "p95_false_glass_cells": "no planner wrote its glass memory",
        "false_glass_cells": "the planner had written no glass memory",
        "median_glass_coverage": "the world has no glass, or no planner wrote its glass memory",
        "glass_coverage": "the world has no glass, or the planner had written no glass memory",
        "heard_panes_found": "the sonar heard no pane, or no planner wrote its glass memory",
        "p05_glass_clearance_m": "the world has no glass",
        "glass_clearance_m": "the world has no glass",
    }
