"""Sharded campaigns: K/N slices that are disjoint and whole, and a merge that gives the unsharded report."""

from __future__ import annotations

import json
import math
import random
from dataclasses import asdict, fields
from pathlib import Path

import pytest

from deploy import strict_json
from deploy.trials import TrialOptions, TrialResult, reachable_starts, summarise_results
from deploy.trials.merge import MergeError, find_reports, merge_reports, read_shard, write_merged
from deploy.trials.records import Shard
from deploy.trials.summary import summary_reasons
from shared.world import load_world

SEED_ROOM = Path(__file__).resolve().parents[3] / "deploy" / "worlds" / "seed_room.yaml"


@pytest.mark.parametrize("count", [1, 2, 3, 7])
def test_shards_are_disjoint_and_together_the_whole_campaign_in_its_order(count: int) -> None:
    starts = reachable_starts(SEED_ROOM, load_world(SEED_ROOM), 10, seed=5)
    slices = [Shard(k, count).select(starts) for k in range(1, count + 1)]
    union = sorted((pair for piece in slices for pair in piece), key=lambda pair: pair[0])
    assert union == list(enumerate(starts))
    assert max(len(s) for s in slices) - min(len(s) for s in slices) <= 1  # balanced


@pytest.mark.parametrize("count", [2, 3, 4])
@pytest.mark.parametrize("per_world", [[1] * 7, [3, 1, 4, 1, 5], [10]])
def test_a_campaigns_trials_are_dealt_out_across_its_worlds(count: int, per_world: list[int]) -> None:
    owners: dict[tuple[int, int], list[int]] = {}
    for k in range(1, count + 1):
        for world, shard in enumerate(Shard(k, count).in_worlds(per_world)):
            if shard is None:
                continue
            for i in range(per_world[world]):
                if shard.owns(i):
                    owners.setdefault((world, i), []).append(k)
    # every trial of every world is run, by exactly one shard
    assert sorted(owners) == [(w, i) for w, n in enumerate(per_world) for i in range(n)]
    assert all(len(ks) == 1 for ks in owners.values())
    loads = [sum(ks == [k] for ks in owners.values()) for k in range(1, count + 1)]
    assert max(loads) - min(loads) <= 1  # balanced over the whole campaign, not per world


def test_a_campaign_of_one_trial_per_room_gives_each_shard_every_nth_room() -> None:
    rooms = [1] * 5  # generated:KIND: one docking in each fresh room
    first = [i for i, shard in enumerate(Shard(1, 2).in_worlds(rooms)) if shard is not None]
    second = [i for i, shard in enumerate(Shard(2, 2).in_worlds(rooms)) if shard is not None]
    assert (first, second) == ([0, 2, 4], [1, 3])
    # a room it runs, it runs whole: its one trial is the shard's
    assert all(shard.owns(0) for shard in Shard(2, 2).in_worlds(rooms) if shard is not None)


@pytest.mark.parametrize("text", ["0/2", "3/2", "1", "a/b", "1/0", "1/2/3"])
def test_a_bad_shard_is_refused_by_name(text: str) -> None:
    with pytest.raises(ValueError, match="shard"):
        Shard.parse(text)


def _campaign(n: int, seed: int = 1) -> list[TrialResult]:
    rng = random.Random(seed)
    trials = []
    for i in range(n):
        docked = rng.random() > 0.1
        trial = TrialResult(
            index=i,
            robot=f"r{i % 2}",
            start=(rng.uniform(0, 4), rng.uniform(0, 4), rng.uniform(-3, 3)),
            docked=docked,
            charging=docked,
            dock_time_s=rng.uniform(6, 30) if docked else math.nan,
            lateral_error_m=rng.uniform(0, 0.004) if docked else math.nan,
            yaw_error_rad=rng.uniform(0, 0.01) if docked else math.nan,
            collisions=int(rng.random() > 0.9),
            path_length_m=rng.uniform(1, 8),
            lower_bound_s=rng.uniform(4, 20) if rng.random() > 0.1 else math.nan,
            wall_s=rng.uniform(1, 5),
            sim_s=rng.uniform(5, 40),
            arrival_speed_mps=rng.uniform(0.07, 0.1) if docked else math.nan,
        )
        trials.append(trial)
    return trials


def _write_report(path: Path, trials: list[TrialResult], options: TrialOptions, wall_s: float) -> Path:
    summary = summarise_results(trials, wall_s, options.controller, "seed_room")
    summary.achieved_rtf = 8.0
    report = {
        "summary": asdict(summary),
        "trials": [asdict(t) for t in trials],
        "errors": [],
        "options": {f.name: str(getattr(options, f.name)) for f in fields(options)},
    }
    path.mkdir(parents=True)
    (path / "trials.json").write_text(strict_json.dumps(report, summary_reasons(summary), indent=2))
    return path


def test_merged_shards_give_the_unsharded_summary_and_trials(tmp_path: Path) -> None:
    trials = _campaign(23)
    whole = summarise_results(trials, 10.0, "graceful", "seed_room")
    shard_dirs = []
    for k in (1, 2, 3):
        shard = Shard(k, 3)
        mine = [t for i, t in shard.select(trials)]
        options = TrialOptions(world=SEED_ROOM, n=23, seed=1, shard=shard, workers=k)  # workers may differ
        shard_dirs.append(
            _write_report(tmp_path / f"shard{k}" / "trials-x-seed_room", mine, options, 10.0 / 3)
        )
    merged = merge_reports(
        [read_shard(p) for p in find_reports([tmp_path / "shard3", tmp_path / "shard1", tmp_path / "shard2"])]
    )
    result = merged["seed_room"]
    assert [t.start for t in result.trials] == [t.start for t in trials]
    assert [t.index for t in result.trials] == list(range(23))
    got, want = result.summary.headline(), whole.headline()
    for key in want:
        if key == "achieved_rtf":
            continue
        assert got[key] == pytest.approx(want[key], nan_ok=True), key
    assert result.summary.achieved_rtf == pytest.approx(8.0)
    out = write_merged(merged, tmp_path / "runs")
    written = json.loads(
        (out / "trials.json").read_text(), parse_constant=lambda c: pytest.fail(f"{c} in the merged report")
    )
    assert written["summary"]["n"] == 23 and (out / "histograms.png").is_file()


def test_merge_refuses_missing_repeated_and_foreign_shards(tmp_path: Path) -> None:
    trials = _campaign(6)
    one, two = Shard(1, 2), Shard(2, 2)
    a = _write_report(
        tmp_path / "a", [t for _, t in one.select(trials)], TrialOptions(world=SEED_ROOM, n=6, shard=one), 1
    )
    b = _write_report(
        tmp_path / "b", [t for _, t in two.select(trials)], TrialOptions(world=SEED_ROOM, n=6, shard=two), 1
    )
    other = _write_report(
        tmp_path / "c",
        [t for _, t in two.select(trials)],
        TrialOptions(world=SEED_ROOM, n=6, seed=9, shard=two),
        1,
    )
    assert merge_reports([read_shard(p) for p in find_reports([a, b])])["seed_room"].summary.n == 6
    with pytest.raises(MergeError, match=r"3 of 6 trials missing \(1, 3, 5\)"):
        merge_reports([read_shard(p) for p in find_reports([a])])
    with pytest.raises(MergeError, match="trial 0 is in both"):
        merge_reports([read_shard(a / "trials.json"), read_shard(a / "trials.json")])
    with pytest.raises(MergeError, match="different campaigns \\(seed 0 against 9\\)"):
        merge_reports([read_shard(p) for p in find_reports([a, other])])
    (tmp_path / "junk.json").write_text("{not json")
    with pytest.raises(MergeError, match="junk.json: not a trials report"):
        read_shard(tmp_path / "junk.json")
    with pytest.raises(MergeError, match="no such file"):
        find_reports([tmp_path / "nowhere"])
