"""`summary.json`: means with 95% confidence intervals per track, the episodes scored, counts and failures.

A pure function of the metric records (plus the run's metadata), so it can be rebuilt from a results directory.
Track keys are `<split>/<task>/<agents>`. Each track holds `episodes`, `failed_episodes`, `episode_ids` (the
episodes scored, sorted), and for the team rows (`team`) and the agent rows (`agent`) each metric's
`{mean, ci_low, ci_high, count}`: a bootstrap interval resampling whole episodes (`intervals.py`, seeded by
`interval_seed(seed, track, "team:<metric>")`, the leaderboard's rule too); `success` also carries the Wilson
score interval `wilson_low`, `wilson_high` with the episodes as trials.
Each track also holds `communication`: messages and bytes sent and the mean bytes per agent-step (also for
the whole run at the top level).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from ..output.records import RESULTS_SCHEMA_VERSION, TEAM
from ..play.channel import communication_stats
from .intervals import cluster_bootstrap_ci, interval_seed, wilson_interval
from .metrics import AGENT_METRICS, TEAM_METRICS

#: Failures listed one by one in summary.json (the rest are counted).
MAX_LISTED_FAILURES = 200


def track_key(split: str, task: str, agents: int) -> str:
    """`<split>/<task>/<agents>`."""
    return f"{split}/{task}/{int(agents)}"


def metric_stats(values: np.ndarray, episodes: np.ndarray, metric: str, seed: int) -> dict[str, float | None]:
    """Mean, episode-resampling bootstrap interval and row count of one metric's rows (`episodes[i]`: the
    episode id of row i; non-finite values left out); a success rate adds its Wilson interval."""
    values = np.asarray(values, dtype=np.float64)
    episodes = np.asarray(episodes).astype(str)
    ok = np.isfinite(values)
    if not ok.any():
        out: dict[str, float | None] = {"mean": None, "ci_low": None, "ci_high": None, "count": 0}
        if metric == "success":
            out |= {"wilson_low": None, "wilson_high": None}
        return out
    mean, lo, hi = cluster_bootstrap_ci(values[ok], episodes[ok], seed)
    out = {"mean": mean, "ci_low": lo, "ci_high": hi, "count": int(ok.sum())}
    if metric == "success":
        w_lo, w_hi = wilson_interval(mean, len(np.unique(episodes[ok])))
        out |= {"wilson_low": w_lo, "wilson_high": w_hi}
    return out


def track_stats(records: pd.DataFrame, key: str, seed: int) -> dict[str, Any]:
    """Statistics of one track's records (team rows and agent rows of its episodes)."""
    team = records[records["agent_index"] == TEAM]
    agent = records[records["agent_index"] != TEAM]
    return {
        "episodes": int(len(team)),
        "failed_episodes": int((team["failure"] != "").sum()),
        "communication": communication_stats(records),
        "episode_ids": sorted(str(e) for e in team["episode_id"]),
        "team": {m: metric_stats(team[m].to_numpy(dtype=np.float64), team["episode_id"].to_numpy(), m,
                                 interval_seed(seed, key, "team:" + m)) for m in TEAM_METRICS},
        "agent": {m: metric_stats(agent[m].to_numpy(dtype=np.float64), agent["episode_id"].to_numpy(), m,
                                  interval_seed(seed, key, "agent:" + m)) for m in AGENT_METRICS},
    }


def build_summary(records: pd.DataFrame, seed: int, meta: dict[str, Any]) -> dict[str, Any]:
    """The summary document: `meta` (submission, dataset, settings, task_rules, toolkit_version) plus counts,
    failures and per-track statistics computed from `records` (with split/task/agents columns)."""
    tracks: dict[str, Any] = {}
    if not records.empty:
        groups = records.groupby(["split", "task", "agents"], observed=True, sort=True)
        for (split, task, agents), frame in groups:
            key = track_key(str(split), str(task), int(agents))
            tracks[key] = track_stats(frame, key, seed)
    team = records[records["agent_index"] == TEAM] if not records.empty else records
    failed = team[team["failure"] != ""] if not team.empty else team
    reasons: dict[str, int] = {}
    for reason in failed["failure"] if not failed.empty else []:
        kind = str(reason).split(":", 1)[0]
        reasons[kind] = reasons.get(kind, 0) + 1
    listed = failed.sort_values("episode_id").head(MAX_LISTED_FAILURES) if not failed.empty else failed
    return {
        "schema_version": RESULTS_SCHEMA_VERSION,
        **meta,
        "counts": {
            "episodes": int(len(team)),
            "agent_rows": int(len(records) - len(team)),
            "failed_episodes": int(len(failed)),
            "failures_by_kind": dict(sorted(reasons.items())),
        },
        "communication": communication_stats(records) if not records.empty else communication_stats(
            pd.DataFrame({"agent_index": [], "steps": []})),
        "failures": [{"episode_id": str(r.episode_id), "reason": str(r.failure)} for r in listed.itertuples()],
        "tracks": tracks,
    }


def finite_or_none(value: float) -> float | None:
    """JSON has no inf/nan: None for a non-finite number."""
    return float(value) if math.isfinite(value) else None
