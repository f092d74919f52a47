"""The published Table 2 board (`leaderboard/table2/`, written by `python tools/table2.py publish`) shows exactly
what its results folders give: every row of its table and of the sub-task table is recomputed here from the
records it ships, every run's submission names the command and commit it trained with, and every run and
baseline was scored on the same val split."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from main_bench.leaderboard.paper_table import PaperRun, paper_markdown, paper_rows, sub_task_markdown
from main_bench.leaderboard.submissions import load_submission
from main_bench.training.campaign import ENVS, ROLLOUT

BOARD = Path(__file__).resolve().parents[2] / "leaderboard" / "table2"


@pytest.fixture(scope="module")
def board():
    doc = json.loads((BOARD / "table2.json").read_text())
    runs = [PaperRun(s["algo"], int(s["seed"]), load_submission(BOARD / s["results"])) for s in doc["scored"]]
    return doc, runs, paper_rows(runs)


def test_the_page_is_its_records(board):
    doc, _, rows = board
    page = (BOARD / "README.md").read_text()
    assert paper_markdown(rows) in page and sub_task_markdown(rows) in page
    assert [(r["algo"], r["agents"]) for r in doc["rows"]] == [(r.algo, r.agents) for r in rows]
    for shown, row in zip(doc["rows"], rows, strict=True):
        assert shown["team_success"] == pytest.approx(row.team_success.mean)
        assert shown["team_spl"] == pytest.approx(row.team_spl.mean)
        assert shown["team_success_by_task"] == pytest.approx({t: e.mean for t, e in row.by_task.items()})
    for figure in ("fig5a_algorithms.png", "fig5b_team_size.png", "fig5c_sub_tasks.png"):
        assert (BOARD / figure).stat().st_size > 1000 and f"({figure})" in page


def test_every_run_names_its_command_and_commit_and_all_share_one_split(board):
    doc, runs, _ = board
    page = (BOARD / "README.md").read_text()
    for name in doc["runs"]:
        algo, agents, seed = re.fullmatch(r"(.+)-n(\d+)-s(\d+)", name).groups()
        meta = json.loads((BOARD / "submissions" / name / "metadata.json").read_text())
        assert meta["algo"] == algo and meta["settings"]["agents"] == int(agents)
        assert meta["settings"]["seed"] == int(seed)
        assert meta["command"].startswith("main-bench train run ") and f"--algo {algo} " in meta["command"]
        assert re.search(r"commit [0-9a-f]{7,}", meta["commit"]) or re.fullmatch(r"[0-9a-f]{7,40}", meta["commit"])
        per_update = ROLLOUT * ENVS * int(agents)
        slots = meta["updates"] * per_update  # the budget: the same agent-step slots for every run
        assert doc["agent_steps_per_run"] <= slots < doc["agent_steps_per_run"] + per_update
        assert f"| {name} | {meta['updates']} | {slots:,} | {meta['agent_steps']:,} |" in page
        assert (BOARD / "submissions" / name / "weights.pt").stat().st_size < 8 * 2**20
    splits = {split for run in runs for split in run.loaded.records["split"].unique()}
    assert splits == {"val"}
    assert not list(BOARD.rglob("checkpoint.pt"))
