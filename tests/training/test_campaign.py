"""The Table 2 campaign: its runs, budgets and commands (`training.campaign`), and `tools/table2.py` end to end
on the tiny data set (train two runs, score them and the random baseline, publish the board)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from main_bench.training.campaign import ENVS, ROLLOUT, Campaign, Cell
from main_bench.training.model import ALGOS

TOOL = Path(__file__).resolve().parents[2] / "tools" / "table2.py"


def test_cells_budgets_and_commands():
    c = Campaign(comm="comm-v")
    cells = c.cells()
    assert [x for x in cells if x.agents == 2 and x.seed == 0] == [Cell(a, 2, 0) for a in ALGOS]
    assert {(x.algo, x.seed) for x in cells if x.agents == 3} == {(a, s) for a in ("ippo", "comm-v") for s in (0, 1, 2)}
    assert {(x.algo, x.seed) for x in cells if x.agents == 2 and x.seed} == {(a, s) for a in ("ippo", "comm-v")
                                                                           for s in (1, 2)}
    assert len({x.name for x in cells}) == len(cells)
    # every algorithm and team size of the board before any second seed
    assert [x.seed for x in cells[:9]] == [0] * 9 and {x.agents for x in cells[7:9]} == {3}
    # then IPPO and the variant in turn, seed by seed, teams of 2 before teams of 3
    assert [x.name for x in cells[9:13]] == ["ippo-n2-s1", "comm-v-n2-s1", "ippo-n2-s2", "comm-v-n2-s2"]
    assert [x.agents for x in cells[9:]] == [2] * 4 + [3] * 4
    for cell in cells:  # the same agent-step budget whatever the team size
        assert c.updates(cell) * ROLLOUT * ENVS * cell.agents >= c.agent_steps
        assert (c.updates(cell) - 1) * ROLLOUT * ENVS * cell.agents < c.agent_steps
    args = c.train_args(Cell("mappo", 2, 0))
    assert args[:2] == ["train", "run"] and args[args.index("--algo") + 1] == "mappo"
    assert args[args.index("--updates") + 1] == str(c.updates(Cell("mappo", 2, 0)))


def test_table2_tool_takes_the_communicating_variant_to_seed(tmp_path):
    """`--comm` names the variant that gets seeds and teams of 3 (the best one once all four are scored);
    anything but a communicating algorithm is refused with exit 2."""
    def status(*extra: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, str(TOOL), "status", "--root", str(tmp_path / "runs"), *extra],
                              capture_output=True, text=True, timeout=120, cwd=tmp_path)

    shown = status("--comm", "comm-v")
    assert shown.returncode == 0, shown.stderr
    names = [line.split()[0] for line in shown.stdout.splitlines()]
    assert "comm-v-n3-s0" in names and "comm-v-n2-s2" in names and "comm-rv-n3-s0" not in names
    assert all(re.search(r" 0/\d+ updates  not started  not scored$", line) for line in shown.stdout.splitlines())
    assert "comm-rv-n3-s0" in [line.split()[0] for line in status().stdout.splitlines()]
    refused = status("--comm", "ippo")
    assert refused.returncode == 2 and "--comm" in refused.stderr


@pytest.mark.slow
def test_table2_tool_trains_scores_and_publishes(tiny_dataset, tmp_path):
    dataset, cache = tiny_dataset
    root, board = tmp_path / "runs", tmp_path / "board"
    common = ["--episodes", str(dataset), "--root", str(root), "--budget", str(ROLLOUT * ENVS * 2),
              "--train-split", "val"]
    env = {"MAIN_BENCH_CACHE": str(cache)}
    import os

    env = {**os.environ, **env}

    def tool(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, str(TOOL), *args, *common], capture_output=True, text=True, env=env,
                              timeout=900, cwd=tmp_path)

    refused = tool("publish", "--out", str(board))
    assert refused.returncode == 2 and "no run is both finished and scored" in refused.stderr
    done = tool("train", "--only", "ippo-n2-s0", "comm-rm-n2-s0")
    assert done.returncode == 0, done.stderr[-2000:]
    assert re.search(r"^ippo-n2-s0 +1/1 updates  finished  not scored$", tool("status").stdout, re.M)
    scored = tool("evaluate")
    assert scored.returncode == 0, scored.stderr[-2000:]
    published = tool("publish", "--out", str(board))
    assert published.returncode == 0, published.stderr[-2000:]
    doc = json.loads((board / "table2.json").read_text())
    assert [r["algo"] for r in doc["rows"]] == ["ippo", "comm-rm", "random"]
    page = (board / "README.md").read_text()
    assert "| comm-rm | 2 | comm |" in page and "| ippo | 2 | silent |" in page and "reference" in page
    assert "| random | 2 | silent |" in page  # a baseline plays each agent on its own, like IPPO
    assert (board / "submissions" / "comm-rm-n2-s0" / "weights.pt").is_file()
    assert not list(board.rglob("checkpoint.pt"))
    assert (board / "fig5a_algorithms.png").stat().st_size > 1000
    assert (board / "fig5c_sub_tasks.png").stat().st_size > 1000 and "fig5c_sub_tasks.png" in page
    assert "Runs on this page: 2 of the campaign's 17; not yet trained and scored: multi-ppo-n2-s0" in page
    assert set(doc["rows"][0]["team_success_by_task"]) == {"individual", "shared"}
