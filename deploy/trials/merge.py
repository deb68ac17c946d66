"""``zendock trials merge``: the shards of one campaign (``trials --shard K/N``) made into its one report.

Each shard wrote a ``trials.json`` per world. Merging checks that they are slices of the same campaign
(same world, number of trials, seed, controller, detector, kind of starts, limits: what decides the starts
and the task, not how many robots or which real-time factor ran them), that no trial is there twice and
none is missing, then computes the summary from the trials themselves with the same code as an unsharded
run, so the medians are over every trial, never medians of shard medians. Wall time is the sum of the
shards' (machine time); the real-time factor is weighted by each shard's wall time.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

from deploy import strict_json
from deploy.paths import new_run_dir
from deploy.trials.records import TrialResult, TrialsSummary
from deploy.trials.summary import combine, summary_reasons

#: The options that make two runs the same campaign; the rest (workers, rtf, compose, shard, where the runs
#: went, the world file's own path on each machine) say only how it ran.
CAMPAIGN_OPTIONS = (
    "n",
    "controller",
    "detector",
    "starts",
    "seed",
    "timeout_sim_s",
    "localisation_error",
    "battery_start",
    "drain_scale",
    "replacements",
)


class MergeError(ValueError):
    """Shard reports that do not make one campaign (named by what is wrong)."""


@dataclass
class ShardReport:
    path: Path
    world: str
    options: dict[str, str]
    summary: TrialsSummary
    trials: list[TrialResult]
    errors: list[str]


def _number(value: Any) -> float:
    return math.nan if value is None else float(value)


def _trial(data: dict[str, Any]) -> TrialResult:
    kwargs: dict[str, Any] = {}
    for f in fields(TrialResult):
        if f.name not in data:
            continue
        value = data[f.name]
        if f.name == "start":
            value = tuple(float(v) for v in value)
        elif f.type in ("float", float):
            value = _number(value)
        kwargs[f.name] = value
    return TrialResult(**kwargs)


def _summary(data: dict[str, Any]) -> TrialsSummary:
    kwargs: dict[str, Any] = {}
    for f in fields(TrialsSummary):
        if f.name in data:
            value = data[f.name]
            kwargs[f.name] = _number(value) if f.type in ("float", float) else value
    return TrialsSummary(**kwargs)


def read_shard(path: Path) -> ShardReport:
    """One world's ``trials.json`` (``MergeError`` naming the file when it is not one)."""
    try:
        data = json.loads(path.read_text())
        summary = _summary(data["summary"])
        trials = [_trial(t) for t in data["trials"]]
        options = {str(k): str(v) for k, v in data["options"].items()}
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise MergeError(f"{path}: not a trials report ({type(exc).__name__}: {exc})") from None
    return ShardReport(path, summary.world, options, summary, trials, list(data.get("errors", [])))


def find_reports(paths: list[Path]) -> list[Path]:
    """``trials.json`` files: given directly, in a run directory, or anywhere under a shard's runs directory."""
    found: list[Path] = []
    for path in paths:
        if path.is_file():
            found.append(path)
        elif path.is_dir():
            reports = sorted(path.rglob("trials.json"))
            if not reports:
                raise MergeError(f"{path}: no trials.json in it")
            found.extend(reports)
        else:
            raise MergeError(f"{path}: no such file or directory")
    return list(dict.fromkeys(p.resolve() for p in found))


def _check_one_campaign(world: str, reports: list[ShardReport]) -> list[TrialResult]:
    first = reports[0]
    for other in reports[1:]:
        for key in CAMPAIGN_OPTIONS:
            if first.options.get(key) != other.options.get(key):
                raise MergeError(
                    f"{world}: {first.path} and {other.path} are different campaigns "
                    f"({key} {first.options.get(key)} against {other.options.get(key)})"
                )
    owner: dict[int, Path] = {}
    trials: list[TrialResult] = []
    for report in reports:
        for trial in report.trials:
            if trial.index in owner:
                raise MergeError(
                    f"{world}: trial {trial.index} is in both {owner[trial.index]} and {report.path}"
                )
            owner[trial.index] = report.path
            trials.append(trial)
    expected = int(first.options.get("n", len(trials)))
    missing = sorted(set(range(expected)) - set(owner))
    if missing:
        shown = ", ".join(map(str, missing[:10])) + (", ..." if len(missing) > 10 else "")
        raise MergeError(
            f"{world}: {len(missing)} of {expected} trials missing ({shown}); is a shard not given?"
        )
    return sorted(trials, key=lambda t: t.index)


@dataclass
class MergedWorld:
    summary: TrialsSummary
    trials: list[TrialResult]
    errors: list[str]
    options: dict[str, str]


def merge_reports(reports: list[ShardReport]) -> dict[str, MergedWorld]:
    """Per world, the campaign's trials and summary from its shards."""
    if not reports:
        raise MergeError("no shard reports to merge")
    by_world: dict[str, list[ShardReport]] = {}
    for report in reports:
        by_world.setdefault(report.world, []).append(report)
    merged: dict[str, MergedWorld] = {}
    for world, group in by_world.items():
        trials = _check_one_campaign(world, group)
        controller = group[0].summary.controller
        # combine() recomputes every statistic from the trials and sums the wall time, as across worlds
        summary = combine([(r.summary, r.trials) for r in group], controller)
        summary.world = world
        options = {**group[0].options, "shard": f"merged from {len(group)}"}
        merged[world] = MergedWorld(summary, trials, [e for r in group for e in r.errors], options)
    return merged


def write_merged(merged: dict[str, MergedWorld], runs_dir: Path) -> Path:
    """Each world's merged ``trials.json`` and histograms under one new run directory; returns it."""
    from deploy.plotting import plot_trial_histograms  # noqa: PLC0415 - matplotlib is slow to import

    out = new_run_dir(runs_dir, "trials-merged-")
    for world, result in merged.items():
        world_dir = out / world if len(merged) > 1 else out
        world_dir.mkdir(parents=True, exist_ok=True)
        report = {
            "summary": asdict(result.summary),
            "trials": [asdict(t) for t in result.trials],
            "errors": result.errors,
            "options": result.options,
        }
        (world_dir / "trials.json").write_text(
            strict_json.dumps(report, summary_reasons(result.summary), indent=2) + "\n"
        )
        plot_trial_histograms(result.trials, world_dir / "histograms.png")
    return out
