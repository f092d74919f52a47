"""`benchmarks.training.training`: the trainer throughput measure and its time split run for real (a tiny
budget) and report every part of the training loop."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.slow


def test_training_measure_reports_rate_and_time_split(tmp_path):
    from main_bench.benchmarks.training import training

    doc = training(1, tmp_path, envs=1, threads=1)
    assert doc["agent_steps"] > 0 and doc["agent_steps_per_s"] > 0 and doc["envs"] == 1
    split = doc["time_split_seconds"]
    assert {"render", "physics", "env_other", "policy_forward", "update"} <= set(split)
    assert split["render"] > 0 and split["update"] > 0  # the timed simulators were the ones the env used
    assert sum(doc["time_split_share_of_loop"].values()) == pytest.approx(1.0, abs=1e-2)
