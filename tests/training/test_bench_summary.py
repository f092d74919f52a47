"""`benchmarks.training`'s text summary reads both committed results (the 2-core machine's, with its full time
split, and the H200's, with the trainer's wait split), and its options refuse a batch too small for its workers."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from main_bench.benchmarks.training import run, summary_lines
from main_bench.errors import InputError

BENCH = Path(__file__).resolve().parents[2] / "docs" / "bench"


@pytest.mark.parametrize("name", ["training.json", "training-h200.json"])
def test_summary_reads_the_committed_results(name):
    result = json.loads((BENCH / name).read_text())
    lines = summary_lines(result)
    rate = f"{result['training']['agent_steps_per_s']} agent-steps/s steady"
    assert any(rate in line for line in lines)
    goal = result["goal"]["training_agent_steps_per_s"]
    assert any(f"(goal {goal:.0f})" in line for line in lines)


def test_the_h200_result_names_its_machine_and_meets_its_goal():
    result = json.loads((BENCH / "training-h200.json").read_text())
    assert "H200" in result["training"]["device"] and result["machine"]["cpus"] == 16
    assert result["goal"]["training_agent_steps_per_s"] == 20_000 and result["training_meets_goal"]


def test_too_few_sub_environments_for_the_workers_are_refused():
    with pytest.raises(InputError, match="--envs 3: needs at least 2 sub-environments per worker"):
        run(envs=3, workers=2)
