"""`leaderboard.paper_table`: the MAIN paper's Table 2 from trained runs. The rows' numbers are recomputed here
from the results folders' records (pooled seeds, team intervals, the seeds' spread, the paired comparison with
IPPO), and the Markdown page shows exactly them."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from lb_fixtures import episodes_dir, make_results  # noqa: F401  (episodes_dir is a fixture)

from main_bench.evaluation.output.records import TEAM
from main_bench.leaderboard.paper_table import PaperRun, paper_markdown, paper_rows, sub_task_markdown
from main_bench.leaderboard.plots import sub_task_bars
from main_bench.leaderboard.submissions import load_submission
from main_bench.numfmt import fraction


@pytest.fixture(scope="module")
def runs(tmp_path_factory, episodes_dir):  # noqa: F811
    base = tmp_path_factory.mktemp("table2")
    made = [("ippo", 0, 0.4, 11), ("ippo", 1, 0.45, 12), ("ippo", 2, 0.35, 13), ("comm-rm", 0, 0.95, 14),
            ("random", 0, 0.05, 15)]
    return [PaperRun(algo, seed, load_submission(make_results(base / f"{algo}-s{seed}", episodes_dir,
                                                              f"{algo} seed {seed}", skill, seed=fixture_seed)))
            for algo, seed, skill, fixture_seed in made]


def _pooled(runs, algo: str, agents: int) -> pd.DataFrame:
    frames = []
    for run in runs:
        if run.algo == algo:
            r = run.loaded.records
            frames.append(r[r["agents"] == agents].assign(seed=run.seed))
    return pd.concat(frames)


def test_rows_are_the_records_pooled_over_seeds(runs):
    rows = paper_rows(runs)
    sizes = sorted({int(a) for run in runs for a in run.loaded.records["agents"].unique()})
    assert [(r.algo, r.agents) for r in rows] == [(a, n) for n in sizes for a in ("ippo", "comm-rm", "random")]
    for row in rows:
        pooled = _pooled(runs, row.algo, row.agents)
        agents, team = pooled[pooled["agent_index"] != TEAM], pooled[pooled["agent_index"] == TEAM]
        for col in ("steps", "distance_to_goal", "success", "spl"):
            assert row.paper[col] == pytest.approx(agents[col].astype(float).mean())
        assert row.team_success.mean == pytest.approx(team["success"].mean())
        assert row.team_spl.mean == pytest.approx(team["spl"].mean())
        assert row.team_success.lo <= row.team_success.mean <= row.team_success.hi
        assert row.seeds == ((0, 1, 2) if row.algo == "ippo" else (0,))
        assert row.seed_success == pytest.approx(tuple(team[team["seed"] == s]["success"].mean() for s in row.seeds))
        if row.algo == "ippo":
            assert row.versus is None
            continue
        ippo = _pooled(runs, "ippo", row.agents)
        ippo_team = ippo[ippo["agent_index"] == TEAM]
        mine = team.groupby(team["task"] + "/" + team["episode_id"])["spl"].mean()
        ref = ippo_team.groupby(ippo_team["task"] + "/" + ippo_team["episode_id"])["spl"].mean()
        common = mine.index.intersection(ref.index)
        assert row.versus.episodes == len(common)
        assert row.versus.difference == pytest.approx(float((mine[common] - ref[common]).mean()))
    better = [r for r in rows if r.algo == "comm-rm"]
    assert all(r.versus.significant and r.versus.difference > 0 for r in better)  # skill 0.95 against 0.4


def test_markdown_shows_every_rows_numbers(runs):
    rows = paper_rows(runs)
    text = paper_markdown(rows)
    lines = [line for line in text.splitlines() if line.startswith("| ") and not line.startswith("| Algorithm")]
    assert len(lines) == len(rows)
    for line, row in zip(lines, rows, strict=True):
        cells = [c.strip() for c in line.strip("|").split("|")]
        assert cells[0] == row.algo and int(cells[1]) == row.agents
        assert float(cells[5]) == pytest.approx(row.paper["steps"], abs=0.05)
        assert float(cells[6]) == pytest.approx(row.paper["distance_to_goal"], abs=0.005)
        assert cells[7] == fraction(row.paper["success"]) and cells[8] == fraction(row.paper["spl"])
        ts, tp = row.team_success, row.team_spl
        assert cells[9].startswith(f"{fraction(ts.mean)} [{fraction(ts.lo)}, {fraction(ts.hi)}] W[")
        assert cells[10] == f"{fraction(tp.mean)} [{fraction(tp.lo)}, {fraction(tp.hi)}]"
        if row.algo == "ippo":
            assert cells[12] == "reference" and len(cells[11].split(",")) == 3
        else:
            assert cells[12].startswith(f"{row.versus.difference:+.3f} [{row.versus.lo:+.3f}, {row.versus.hi:+.3f}]")
    assert np.isfinite([r.team_spl.mean for r in rows]).all()


def test_sub_task_success_is_each_sub_tasks_team_records_and_the_figure_draws_them(runs):
    rows = paper_rows(runs)
    for row in rows:
        pooled = _pooled(runs, row.algo, row.agents)
        team = pooled[pooled["agent_index"] == TEAM]
        assert sorted(row.by_task) == sorted(team["task"].unique())
        for task, est in row.by_task.items():
            assert est.mean == pytest.approx(team[team["task"] == task]["success"].mean())
            assert est.lo <= est.mean <= est.hi and est.wilson is not None
    text = sub_task_markdown(rows)
    lines = [line for line in text.splitlines() if line.startswith("| ") and not line.startswith("| Algorithm")]
    tasks = sorted({t for r in rows for t in r.by_task})
    for line, row in zip(lines, rows, strict=True):
        cells = [c.strip() for c in line.strip("|").split("|")]
        assert cells[:2] == [row.algo, str(row.agents)]
        for cell, task in zip(cells[2:], tasks, strict=True):
            e = row.by_task[task]
            assert cell == f"{fraction(e.mean)} [{fraction(e.lo)}, {fraction(e.hi)}]"
    figure = sub_task_bars(rows)
    assert figure.png.startswith(b"\x89PNG") and len(figure.table) == sum(len(r.by_task) for r in rows)
    assert figure.table["mean"].tolist() == pytest.approx([e.mean for r in rows for e in r.by_task.values()])
