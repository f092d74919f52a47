"""The MAIN paper's Table 2 from trained runs: one row per (algorithm, team size), with intervals, the spread over
training seeds and a paired comparison against a reference algorithm (IPPO).

Flows in: the results folders of trained submissions, each named with its algorithm and training seed
(`PaperRun`), all scored on the same split. Flows out: `PaperRow`s and their Markdown table. Every number is a
pure function of the records:

- Length, Distance, Success, SPL: the paper's columns, means over agent rows (steps; metres to the target's
  success region; fractions), every seed's episodes pooled.
- Team success and team SPL: means over team rows with 95% bootstrap intervals that resample episodes (a seed's
  repeat of an episode stays with it: `cluster_bootstrap_ci`), and the Wilson interval for success.
- Sub-tasks: team success on each sub-task (shared, individual) with its 95% interval, for Fig. 5(c).
- Seed spread: the team success of each seed's run, when there are several.
- Versus the reference: the paired bootstrap of team SPL over the episodes both rows were scored on (each
  episode's value averaged over seeds first), "significant" when the 95% interval excludes 0.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..evaluation.output.records import TEAM
from ..evaluation.scoring.intervals import PairedDifference, interval_seed, paired_difference
from ..numfmt import fraction
from .submissions import LoadedSubmission
from .tables import Estimate, TableSettings, estimate

#: The paper's columns: (agent-row column, title, unit shown in the note).
PAPER_COLUMNS: tuple[tuple[str, str], ...] = (("steps", "Length"), ("distance_to_goal", "Distance"),
                                               ("success", "Success"), ("spl", "SPL"))


@dataclass(frozen=True)
class PaperRun:
    """One trained run's scored results: its algorithm (`--algo`), training seed and evaluation mode."""

    algo: str
    seed: int
    loaded: LoadedSubmission


@dataclass(frozen=True)
class PaperRow:
    """One (algorithm, team size) row of the table (see the module docstring)."""

    algo: str
    agents: int
    mode: str
    seeds: tuple[int, ...]
    episodes: int
    paper: dict[str, float]
    team_success: Estimate
    team_spl: Estimate
    seed_success: tuple[float, ...]
    versus: PairedDifference | None
    #: team success per sub-task ("individual", "shared"), over that sub-task's episodes
    by_task: dict[str, Estimate]


def _rows_of(runs: Sequence[PaperRun], agents: int) -> pd.DataFrame:
    frames = []
    for run in runs:
        r = run.loaded.records
        mine = r[r["agents"] == agents].copy()
        mine["seed"] = run.seed
        frames.append(mine)
    return pd.concat(frames, ignore_index=True)


def _team_spl_by_episode(team: pd.DataFrame) -> dict[str, float]:
    means = team.groupby(team["task"].astype(str) + "/" + team["episode_id"].astype(str))["spl"].mean()
    return {str(k): float(v) for k, v in means.items()}


def paper_rows(runs: Sequence[PaperRun], reference: str = "ippo",
               settings: TableSettings = TableSettings()) -> list[PaperRow]:
    """The table's rows, ordered by team size, then algorithm as `runs` first name them."""
    order = list(dict.fromkeys(run.algo for run in runs))
    sizes = sorted({int(a) for run in runs for a in run.loaded.records["agents"].unique()})
    out = []
    for n in sizes:
        by_algo = {a: [r for r in runs if r.algo == a and (r.loaded.records["agents"] == n).any()] for a in order}
        records = {a: _rows_of(mine, n) for a, mine in by_algo.items() if mine}
        ref_team = None
        if reference in records:
            rows = records[reference]
            ref_team = _team_spl_by_episode(rows[rows["agent_index"] == TEAM])
        for algo, rows in records.items():
            mine = by_algo[algo]
            agents_rows, team = rows[rows["agent_index"] != TEAM], rows[rows["agent_index"] == TEAM]
            key = f"table2/{algo}/{n}"
            clusters = (team["task"].astype(str) + "/" + team["episode_id"].astype(str)).to_numpy()
            versus = None
            if ref_team is not None and algo != reference:
                versus = paired_difference(_team_spl_by_episode(team), ref_team,
                                           interval_seed(settings.seed, key, "paired:spl"), settings.n_resamples,
                                           settings.level)
            seeds = tuple(sorted(int(s) for s in team["seed"].unique()))
            out.append(PaperRow(
                algo=algo, agents=n, mode=mine[0].loaded.submission.mode, seeds=seeds, episodes=len(set(clusters)),
                paper={col: float(agents_rows[col].astype(float).mean()) for col, _ in PAPER_COLUMNS},
                team_success=estimate(team["success"].astype(float).to_numpy(), settings, key, "team:success", clusters),
                team_spl=estimate(team["spl"].astype(float).to_numpy(), settings, key, "team:spl", clusters),
                seed_success=tuple(float(team[team["seed"] == s]["success"].astype(float).mean()) for s in seeds),
                versus=versus, by_task=_by_task(team, clusters, settings, key)))
    return out


def _by_task(team: pd.DataFrame, clusters: np.ndarray, settings: TableSettings, key: str) -> dict[str, Estimate]:
    tasks = team["task"].astype(str).to_numpy()
    success = team["success"].astype(float).to_numpy()
    return {task: estimate(success[tasks == task], settings, f"{key}/{task}", "team:success", clusters[tasks == task])
            for task in sorted(set(tasks))}


def _versus_cell(row: PaperRow, reference: str) -> str:
    v = row.versus
    if row.algo == reference:
        return "reference"
    if v is None or np.isnan(v.difference):
        return "–"
    verdict = "tie" if v.tie else ("significant" if v.significant else "not significant")
    return f"{v.difference:+.3f} [{v.lo:+.3f}, {v.hi:+.3f}] {verdict}"


def paper_markdown(rows: Sequence[PaperRow], reference: str = "ippo") -> str:
    """The table as Markdown: the paper's four columns, then team success and SPL with intervals, the seeds'
    spread and the paired comparison with `reference`."""
    head = ["Algorithm", "N", "mode", "seeds", "episodes", "Length", "Distance", "Success", "SPL",
            "team success [95% CI] W[Wilson]", "team SPL [95% CI]", "team success per seed",
            f"team SPL vs {reference} (paired)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join([":---"] * 3 + ["---:"] * (len(head) - 3)) + "|"]
    for r in rows:
        ts, tp = r.team_success, r.team_spl
        wilson = "" if ts.wilson is None else f" W[{fraction(ts.wilson[0])}, {fraction(ts.wilson[1])}]"
        spread = ", ".join(fraction(v) for v in r.seed_success) if len(r.seeds) > 1 else "–"
        cells = [r.algo, str(r.agents), r.mode, ",".join(map(str, r.seeds)), str(r.episodes),
                 f"{r.paper['steps']:.1f}", f"{r.paper['distance_to_goal']:.2f}", fraction(r.paper["success"]),
                 fraction(r.paper["spl"]), f"{fraction(ts.mean)} [{fraction(ts.lo)}, {fraction(ts.hi)}]{wilson}",
                 f"{fraction(tp.mean)} [{fraction(tp.lo)}, {fraction(tp.hi)}]", spread, _versus_cell(r, reference)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def sub_task_markdown(rows: Sequence[PaperRow]) -> str:
    """Team success per sub-task and row, with 95% bootstrap intervals, as Markdown (Fig. 5(c)'s numbers)."""
    tasks = sorted({t for r in rows for t in r.by_task})
    lines = ["| Algorithm | N | " + " | ".join(f"team success, {t} [95% CI]" for t in tasks) + " |",
             "|:---|---:|" + "---:|" * len(tasks)]
    for r in rows:
        cells = [f"{fraction(e.mean)} [{fraction(e.lo)}, {fraction(e.hi)}]" if (e := r.by_task.get(t)) else "–"
                 for t in tasks]
        lines.append(f"| {r.algo} | {r.agents} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
