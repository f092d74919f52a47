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


PAPER_PAGE = BOARD.parents[1] / "docs" / "paper.md"


def _table(page: str, header: str) -> list[list[str]]:
    """The body rows (lists of cells) of the Markdown table whose header row starts with `| {header} |`."""
    lines = page.splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith(f"| {header} |"))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip().strip("|").split("|")])
    return rows


def test_the_paper_page_shows_the_boards_numbers():
    """docs/paper.md's tables of teams of 2 and 3 and its run count show the board's cells: team success and SPL
    with their intervals, each seed's team success, both sub-tasks' team success, the paired column."""
    readme = (BOARD / "README.md").read_text()
    paper = PAPER_PAGE.read_text()
    done, total = re.search(r"Runs on this page: (\d+) of the campaign's (\d+)", readme).groups()
    count = f"All {total} runs" if done == total else f"{done} of the {total} runs"
    assert f"{count} are trained and scored" in paper
    # Algorithm | N | mode | seeds | episodes | Length | Distance | Success | SPL | team success W | team SPL |
    # per seed | paired
    main = {(r[0], int(r[1])): r for r in _table(readme, "Algorithm")}
    by_task = {(r[0], int(r[1])): r[2:] for r in _table(readme, "Algorithm | N | team success, individual [95% CI]")}
    for agents in (2, 3):
        rows = _table(paper, f"algorithm, teams of {agents}")
        assert sorted(r[0].lower() for r in rows) == sorted(a for a, n in main if n == agents), agents
        for row in rows:
            key = (row[0].lower(), agents)
            cells = main[key]
            if agents == 2:  # the column of each seed's team success
                seeds, per_seed = cells[3].split(","), cells[11]
                values = per_seed.split(", ") if per_seed != "–" else [cells[9].split(" ")[0]]
                expected = "" if key[0] == "random" else "; ".join(f"{s}: {v}" for s, v in zip(seeds, values, strict=True))
                assert row[1] == expected, key
                row = row[1:]
            individual, shared = by_task[key]
            assert row[1:6] == [cells[9].split(" W[")[0], cells[10], shared, individual,
                                cells[12].replace("] ", "], ")], key
