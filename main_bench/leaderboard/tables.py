"""Leaderboard tables: per-track rankings with bootstrap intervals, and the MAIN paper's Table 2 shape.

A track is one (split, task, number of agents). Every number is a mean over the episodes' team records with
its 95% bootstrap confidence interval resampling episodes, seeded by the rule `summary.json` uses
(`main_bench.evaluation.scoring.intervals`), so both print the same digits; success rates also carry their Wilson
score interval. Adjacent methods of a track are compared by a paired bootstrap of team SPL over the episodes
both were scored on (`TrackEntry.versus_next`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import pandas as pd

from ..evaluation.scoring.intervals import (
    PairedDifference,
    cluster_bootstrap_ci,
    interval_seed,
    paired_difference,
    wilson_interval,
)
from .submissions import LoadedSubmission, Submission

#: Team metrics shown per track: (record column, column title).
TRACK_METRICS: tuple[tuple[str, str], ...] = (
    ("success", "Success"),
    ("spl", "SPL"),
    ("soft_spl", "Soft SPL"),
    ("distance_to_goal", "Distance to goal (m)"),
    ("steps", "Episode length (steps)"),
    ("collisions", "Collisions"),
)
#: The MAIN paper's Table 2 columns per agent count: (record column, title).
TABLE2_METRICS: tuple[tuple[str, str], ...] = (
    ("steps", "Length"),
    ("distance_to_goal", "Distance"),
    ("success", "Success rate"),
    ("spl", "SPL"),
)


@dataclass(frozen=True)
class TableSettings:
    """How intervals are computed: bootstrap resamples, confidence level and seed."""

    seed: int = 0
    n_resamples: int = 2000
    level: float = 0.95


@dataclass(frozen=True)
class Estimate:
    """A mean over episodes, its bootstrap confidence interval, and for success rates the Wilson interval."""

    mean: float
    lo: float
    hi: float
    wilson: tuple[float, float] | None = None


@dataclass(frozen=True)
class TrackEntry:
    """One submission's row in a track table."""

    submission: Submission
    rank: int
    episodes: int
    metrics: Mapping[str, Estimate]
    bytes_per_step: float | None = None  # mean message bytes per agent-step; None in central mode (not measured)
    #: Team SPL against the next entry of the table (None for the last): paired bootstrap over shared episodes.
    versus_next: PairedDifference | None = None

    @property
    def versus_label(self) -> str:
        """"tie", "significant" or "not significant" (against the next entry), "" for the last entry."""
        v = self.versus_next
        if v is None:
            return ""
        if v.tie:
            return "tie"
        return "significant" if v.significant else "not significant"


@dataclass(frozen=True)
class TrackTable:
    """The ranked table of one track (split, task, agents), best team SPL first."""

    split: str
    task: str
    agents: int
    entries: tuple[TrackEntry, ...]

    @property
    def key(self) -> str:
        """`<split>/<task>/<agents>`, the key summary.json and leaderboard.json use."""
        return f"{self.split}/{self.task}/{self.agents}"


@dataclass(frozen=True)
class Table2:
    """MAIN Table 2 for one (split, task): methods as rows, one column group per agent count.

    `cells[name][agents][metric]` is an Estimate, or absent where the method was not scored on that track.
    """

    split: str
    task: str
    agent_counts: tuple[int, ...]
    methods: tuple[Submission, ...]
    cells: Mapping[str, Mapping[int, Mapping[str, Estimate]]]


def estimate(values: np.ndarray, settings: TableSettings, key: str = "", name: str = "",
             episodes: np.ndarray | None = None) -> Estimate:
    """Mean and bootstrap interval of `values` (rows of `episodes`, resampled by episode), seeded by
    `interval_seed(settings.seed, key, name)`; `name` "team:success" adds the Wilson interval."""
    values = np.asarray(values, dtype=np.float64)
    ok = np.isfinite(values)
    clusters = None if episodes is None else np.asarray(episodes).astype(str)[ok]
    mean, lo, hi = cluster_bootstrap_ci(values[ok], clusters, interval_seed(settings.seed, key, name),
                                        n_resamples=settings.n_resamples, level=settings.level)
    wilson = None
    if name.endswith(":success"):
        trials = len(np.unique(clusters)) if clusters is not None else int(ok.sum())
        wilson = wilson_interval(mean, trials, settings.level)
    return Estimate(float(mean), float(lo), float(hi), wilson)


def track_keys(subs: list[LoadedSubmission]) -> list[tuple[str, str, int]]:
    """Every (split, task, agents) any submission has team records for, sorted."""
    keys: set[tuple[str, str, int]] = set()
    for s in subs:
        t = s.teams
        keys.update(zip(t["split"], t["task"], t["agents"].astype(int), strict=True))
    return sorted(keys, key=lambda k: (k[0], k[1], k[2]))


def _metrics_of(team: pd.DataFrame, columns: tuple[tuple[str, str], ...], settings: TableSettings, key: str
                ) -> dict[str, Estimate]:
    ids = team["episode_id"].to_numpy()
    return {col: estimate(team[col].to_numpy(), settings, key, "team:" + col, ids) for col, _ in columns}


def track_table(subs: list[LoadedSubmission], split: str, task: str, agents: int,
                settings: TableSettings) -> TrackTable:
    """Rank the submissions scored on one track by team SPL (then success, then name); ties share a rank."""
    from ..evaluation.play.channel import communication_stats

    key = f"{split}/{task}/{agents}"
    rows = []
    talk: dict[str, float | None] = {}
    for s in subs:
        t = s.teams
        team = t[(t["split"] == split) & (t["task"] == task) & (t["agents"] == agents)]
        if team.empty:
            continue
        spl = dict(zip(team["episode_id"].astype(str), team["spl"].astype(float), strict=True))
        rows.append((s.submission, len(team), _metrics_of(team, TRACK_METRICS, settings, key), spl))
        r = s.records
        mine = r[(r["split"] == split) & (r["task"] == task) & (r["agents"] == agents)]
        talk[s.submission.name] = (None if s.submission.mode == "central"
                                   else float(communication_stats(mine)["bytes_per_agent_step"]))
    rows.sort(key=lambda r: (-r[2]["spl"].mean, -r[2]["success"].mean, r[0].name))
    entries: list[TrackEntry] = []
    for i, (sub, n, metrics, spl) in enumerate(rows):
        rank = i + 1
        if entries:
            prev = entries[-1]
            if (prev.metrics["spl"].mean, prev.metrics["success"].mean) == (metrics["spl"].mean,
                                                                            metrics["success"].mean):
                rank = prev.rank
        versus = None
        if i + 1 < len(rows):
            versus = paired_difference(spl, rows[i + 1][3], interval_seed(settings.seed, key, "paired:spl"),
                                       settings.n_resamples, settings.level)
        entries.append(TrackEntry(sub, rank, n, MappingProxyType(metrics), talk[sub.name], versus))
    return TrackTable(split, task, agents, tuple(entries))


def table2(subs: list[LoadedSubmission], split: str, task: str, tracks: list[TrackTable],
           settings: TableSettings) -> Table2:
    """MAIN Table 2 for one split and task; methods ordered by their rank on the largest team size."""
    mine = [t for t in tracks if t.split == split and t.task == task]
    counts = tuple(sorted({t.agents for t in mine}))
    order: list[Submission] = []
    for t in sorted(mine, key=lambda t: -t.agents):
        for e in t.entries:
            if e.submission not in order:
                order.append(e.submission)
    cells: dict[str, dict[int, Mapping[str, Estimate]]] = {}
    for t in mine:
        for e in t.entries:
            cells.setdefault(e.submission.name, {})[t.agents] = MappingProxyType(
                {col: e.metrics[col] for col, _ in TABLE2_METRICS})
    return Table2(split, task, counts, tuple(order),
                  MappingProxyType({k: MappingProxyType(v) for k, v in cells.items()}))


def build_tables(subs: list[LoadedSubmission], settings: TableSettings) -> tuple[list[TrackTable], list[Table2]]:
    """All track tables of one data set's submissions, and one Table 2 per (split, task)."""
    tracks = [track_table(subs, *k, settings) for k in track_keys(subs)]
    pairs = sorted({(t.split, t.task) for t in tracks})
    return tracks, [table2(subs, split, task, tracks, settings) for split, task in pairs]
